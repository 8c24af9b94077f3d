// `sgdicp bench PAIRS_FILE...`: registers every pair of pairs files against their ground truth
// and prints per-pair errors and times and a summary.
#include <unistd.h>
#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <optional>
#include <random>
#include <sstream>
#include <thread>

#include "cli_common.hpp"
#include "cli_settings.hpp"
#include "help_layout.hpp"
#include "sgdicp/core/error.hpp"
#include "sgdicp/metrics/metrics.hpp"
#include "sgdicp/tools/pairs.hpp"

namespace sgdicp::cli {
namespace {

struct BenchOptions {
  std::vector<std::string> pairs_files;
  std::string perturb;
  std::size_t repeat = 1;
  std::size_t jobs = 1;
  std::string csv;
  std::vector<std::string> success = {"0.05,1", "2,5"};
  SettingsOptions settings;
  DepthOptions depth;
};

struct Perturbation {
  double translation_m = 0.0;
  double rotation_rad = 0.0;
  std::uint64_t seed = 1;
};

struct Threshold {
  double translation_m;
  double rotation_deg;
};

struct Row {
  std::string pairs_file;
  std::size_t line = 0;
  std::string source;
  std::string reference;
  std::string method;
  std::size_t repeat = 0;
  double t_err = 0, r_err_sum = 0, r_err_geo_deg = 0;
  double init_t_err = 0, init_r_geo_deg = 0;
  double build_ms = 0, align_ms = 0;
  std::size_t iterations = 0, points = 0, source_points = 0;
  bool converged = false;
  bool degenerate = false;
  std::string stop_reason;
  std::string source_path, reference_path;  // as the pairs file gives them
};

std::string number(double v, int digits) {
  std::array<char, 32> text{};
  std::snprintf(text.data(), text.size(), "%.*g", digits, v);
  return text.data();
}

// The --csv columns, each name beside how its value is written: the header and the rows cannot
// drift apart.
struct CsvColumn {
  const char* name;
  std::string (*value)(const Row&);
};
const std::array<CsvColumn, 20> kCsvColumns{{
    {"pairs_file", [](const Row& r) { return r.pairs_file; }},
    {"line", [](const Row& r) { return std::to_string(r.line); }},
    {"source", [](const Row& r) { return r.source_path; }},
    {"reference", [](const Row& r) { return r.reference_path; }},
    {"method", [](const Row& r) { return r.method; }},
    {"repeat", [](const Row& r) { return std::to_string(r.repeat); }},
    {"translation_error_m", [](const Row& r) { return number(r.t_err, 9); }},
    {"rotation_error_euler_rad", [](const Row& r) { return number(r.r_err_sum, 9); }},
    {"rotation_error_geodesic_deg", [](const Row& r) { return number(r.r_err_geo_deg, 9); }},
    {"initial_translation_error_m", [](const Row& r) { return number(r.init_t_err, 9); }},
    {"initial_rotation_error_deg", [](const Row& r) { return number(r.init_r_geo_deg, 9); }},
    {"build_ms", [](const Row& r) { return number(r.build_ms, 6); }},
    {"align_ms", [](const Row& r) { return number(r.align_ms, 6); }},
    {"time_ms", [](const Row& r) { return number(r.build_ms + r.align_ms, 6); }},
    {"iterations", [](const Row& r) { return std::to_string(r.iterations); }},
    {"points_processed", [](const Row& r) { return std::to_string(r.points); }},
    {"source_points", [](const Row& r) { return std::to_string(r.source_points); }},
    {"converged", [](const Row& r) { return std::string(r.converged ? "1" : "0"); }},
    {"stop_reason", [](const Row& r) { return r.stop_reason; }},
    {"degenerate", [](const Row& r) { return std::string(r.degenerate ? "1" : "0"); }},
}};

void write_csv_line(std::FILE* csv, const Row* row) {
  std::string line;
  for (const auto& column : kCsvColumns) {
    if (!line.empty()) line += ',';
    line += row ? column.value(*row) : std::string(column.name);
  }
  std::fprintf(csv, "%s\n", line.c_str());
}

std::vector<double> parse_numbers(const std::string& text, const std::string& what) {
  std::vector<double> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    try {
      std::size_t used = 0;
      out.push_back(std::stod(item, &used));
      if (used != item.size()) throw std::invalid_argument(item);
    } catch (const std::exception&) {
      throw InvalidSettingsError(what + ": '" + item + "' is not a number");
    }
    if (!std::isfinite(out.back()) || out.back() < 0) {
      throw InvalidSettingsError(what + ": values must be finite and non-negative");
    }
  }
  return out;
}

// Uniform double in [0, 1) from the generator's raw bits (portable, unlike std distributions).
double uniform01(std::mt19937_64& rng) {
  return static_cast<double>(rng() >> 11) * 0x1.0p-53;
}

Eigen::Vector3d random_unit_vector(std::mt19937_64& rng) {
  while (true) {
    const Eigen::Vector3d v(2 * uniform01(rng) - 1, 2 * uniform01(rng) - 1, 2 * uniform01(rng) - 1);
    const double n = v.norm();
    if (n > 1e-3 && n <= 1.0) return v / n;
  }
}

// T_init = perturbation composed with T_gt such that translation_error(T_init, T_gt) and
// rotation_error_geodesic(T_init, T_gt) are exactly the requested sizes.
Eigen::Matrix4d perturbed(const Eigen::Matrix4d& T_gt, const Perturbation& p, std::uint64_t salt) {
  std::mt19937_64 rng(p.seed * 0x9E3779B97F4A7C15ULL + salt);
  const Eigen::Vector3d dt = random_unit_vector(rng) * p.translation_m;
  const Eigen::Matrix3d dr =
      Eigen::AngleAxisd(p.rotation_rad, random_unit_vector(rng)).toRotationMatrix();
  Eigen::Matrix4d T = T_gt;
  T.topLeftCorner<3, 3>() = dr * T_gt.topLeftCorner<3, 3>();
  T.topRightCorner<3, 1>() += dt;
  return T;
}

struct Stats {
  double median = 0, mean = 0, std = 0;
};
Stats stats_of(std::vector<double> v) {
  Stats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  s.median = n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
  for (const double x : v) s.mean += x;
  s.mean /= static_cast<double>(n);
  for (const double x : v) s.std += (x - s.mean) * (x - s.mean);
  s.std = n > 1 ? std::sqrt(s.std / static_cast<double>(n - 1)) : 0.0;
  return s;
}

std::string fmt(double v, int precision = 4) {
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.*g", precision, v);
  return buf;
}

std::vector<std::string> split_commas(const std::string& text) {
  std::vector<std::string> out;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (!item.empty()) out.push_back(item);
  }
  return out;
}

// The statistics of a group of registrations, shared by the summary and the comparison table.
struct Summary {
  Stats t_err, r_err_sum, r_err_geo, time, points, iterations;
  std::size_t n = 0;
  std::size_t converged = 0;
  std::vector<std::size_t> successes;  // per threshold
};

Summary summarize(const std::vector<const Row*>& rows, const std::vector<Threshold>& thresholds) {
  std::vector<double> te, rs, rg, tm, pts, its;
  Summary s;
  s.n = rows.size();
  s.successes.assign(thresholds.size(), 0);
  for (const Row* r : rows) {
    te.push_back(r->t_err);
    rs.push_back(r->r_err_sum);
    rg.push_back(r->r_err_geo_deg);
    tm.push_back(r->build_ms + r->align_ms);
    pts.push_back(static_cast<double>(r->points));
    its.push_back(static_cast<double>(r->iterations));
    s.converged += r->converged ? 1 : 0;
    for (std::size_t t = 0; t < thresholds.size(); ++t) {
      s.successes[t] +=
          (r->t_err < thresholds[t].translation_m && r->r_err_geo_deg < thresholds[t].rotation_deg)
              ? 1
              : 0;
    }
  }
  s.t_err = stats_of(te);
  s.r_err_sum = stats_of(rs);
  s.r_err_geo = stats_of(rg);
  s.time = stats_of(tm);
  s.points = stats_of(pts);
  s.iterations = stats_of(its);
  return s;
}

std::string percent(std::size_t k, std::size_t n) {
  return fmt(n ? 100.0 * static_cast<double>(k) / static_cast<double>(n) : 0.0, 3);
}

void print_summary(const std::string& label, const std::vector<const Row*>& rows,
                   const std::vector<Threshold>& thresholds) {
  const Summary s = summarize(rows, thresholds);
  const auto line = [](const char* what, const Stats& st, const char* unit) {
    std::printf("  %-28s median %-10s mean %s +- %s %s\n", what, fmt(st.median).c_str(),
                fmt(st.mean).c_str(), fmt(st.std).c_str(), unit);
  };
  std::printf("\nsummary over %zu registrations (%s)\n", s.n, label.c_str());
  line("translation error", s.t_err, "m");
  line("rotation error (sum |d rpy|)", s.r_err_sum, "rad");
  line("rotation error (geodesic)", s.r_err_geo, "deg");
  line("time (prepare + register)", s.time, "ms, file I/O excluded");
  line("points processed", s.points, "");
  line("iterations", s.iterations, "");
  std::printf("  converged: %zu/%zu\n", s.converged, s.n);
  for (std::size_t t = 0; t < thresholds.size(); ++t) {
    std::printf("  success (t_err < %s m and r_geo < %s deg): %zu/%zu = %s %%\n",
                fmt(thresholds[t].translation_m).c_str(), fmt(thresholds[t].rotation_deg).c_str(),
                s.successes[t], s.n, percent(s.successes[t], s.n).c_str());
  }
}

// One line per method: the comparison table of a multi-method run.
void print_comparison(const std::vector<std::string>& methods, const std::vector<Row>& rows,
                      const std::vector<Threshold>& thresholds) {
  std::printf("\n%-10s %5s %12s %12s %12s %10s %10s %5s", "method", "n", "t_err med[m]",
              "r_geo med[°]", "time med[ms]", "points med", "iters med", "conv");
  for (const auto& th : thresholds) {
    std::printf(" %14s",
                ("ok<" + fmt(th.translation_m, 3) + "m," + fmt(th.rotation_deg, 3) + "°").c_str());
  }
  std::printf("\n");
  for (const auto& m : methods) {
    std::vector<const Row*> mine;
    for (const auto& r : rows) {
      if (r.method == m) mine.push_back(&r);
    }
    const Summary s = summarize(mine, thresholds);
    std::printf("%-10s %5zu %12s %12s %12s %10s %10s %5zu", m.c_str(), s.n,
                fmt(s.t_err.median).c_str(), fmt(s.r_err_geo.median).c_str(),
                fmt(s.time.median).c_str(), fmt(s.points.median).c_str(),
                fmt(s.iterations.median).c_str(), s.converged);
    for (const std::size_t k : s.successes) std::printf(" %13s%%", percent(k, s.n).c_str());
    std::printf("\n");
  }
}

std::vector<MethodSpec> make_methods(const std::vector<std::string>& names,
                                     const SettingsOptions& settings) {
  if (names.empty()) throw InvalidSettingsError("--method: no method given");
  std::vector<MethodSpec> methods;
  for (const auto& name : names) methods.push_back(make_method(name, settings));
  return methods;
}

std::optional<Perturbation> parse_perturbation(const std::string& text) {
  if (text.empty()) return std::nullopt;
  const auto v = parse_numbers(text, "--perturb");
  if (v.size() < 2 || v.size() > 3) {
    throw InvalidSettingsError("--perturb expects TRANS_M,ROT_RAD[,SEED]");
  }
  if (v[1] > std::numbers::pi) throw InvalidSettingsError("--perturb: rotation must be <= pi");
  return Perturbation{v[0], v[1], v.size() == 3 ? static_cast<std::uint64_t>(v[2]) : 1};
}

std::vector<Threshold> parse_thresholds(const std::vector<std::string>& texts) {
  std::vector<Threshold> thresholds;
  for (const auto& s : texts) {
    const auto v = parse_numbers(s, "--success");
    if (v.size() != 2) throw InvalidSettingsError("--success expects TRANS_M,ROT_DEG");
    thresholds.push_back({v[0], v[1]});
  }
  return thresholds;
}

// A registration problem and the pairs file it comes from.
using Job = std::pair<std::string, RegistrationPair>;

std::vector<Job> read_jobs(const std::vector<std::string>& pairs_files) {
  std::vector<Job> jobs;
  for (const auto& file : pairs_files) {
    for (auto& p : read_pairs_file(file)) jobs.emplace_back(file, std::move(p));
  }
  return jobs;
}

using CsvFile = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

// The --csv file with its header written; none without --csv.
CsvFile open_csv(const std::string& path) {
  CsvFile csv(nullptr, &std::fclose);
  if (path.empty()) return csv;
  csv.reset(std::fopen(path.c_str(), "w"));
  if (!csv) throw IoError(path + ": cannot open for writing");
  write_csv_line(csv.get(), nullptr);  // the header
  return csv;
}

Row make_row(const Job& job, const std::string& method, std::size_t rep,
             const Eigen::Matrix4d& T_init, const MethodRun& run) {
  const auto& [file, pair] = job;
  const Eigen::Matrix4d& T_gt = pair.T_reference_source_gt;
  const RegistrationResult& r = run.result;
  Row row;
  row.pairs_file = file;
  row.line = pair.line;
  row.source = pair.source.filename().string();
  row.reference = pair.reference.filename().string();
  row.source_path = pair.source.string();
  row.reference_path = pair.reference.string();
  row.method = method;
  row.repeat = rep;
  row.t_err = translation_error(r.T_reference_source, T_gt);
  row.r_err_sum = rotation_error_euler_sum(r.T_reference_source, T_gt);
  row.r_err_geo_deg =
      rotation_error_geodesic(r.T_reference_source, T_gt) * 180.0 / std::numbers::pi;
  row.init_t_err = translation_error(T_init, T_gt);
  row.init_r_geo_deg = rotation_error_geodesic(T_init, T_gt) * 180.0 / std::numbers::pi;
  row.build_ms = run.prepare_ms;
  row.align_ms = r.time_ms;
  row.iterations = r.iterations;
  row.points = r.points_processed;
  row.source_points = run.source_points;
  row.converged = r.converged;
  row.degenerate = r.degenerate;
  row.stop_reason = std::string(to_string(r.stop_reason));
  return row;
}

void print_row_header() {
  std::printf("%-4s %-36s %-9s %3s %10s %10s %9s %9s %6s %9s %4s\n", "#",
              "pair (source <- reference)", "method", "rep", "t_err[m]", "r_sum[rad]", "r_geo[deg]",
              "time[ms]", "iters", "points", "conv");
}

void print_row(const Row& row, std::size_t pair_number) {
  const std::string name = row.source + " <- " + row.reference;
  std::printf("%-4zu %-36s %-9s %3zu %10s %10s %9s %9s %6zu %9zu %4s\n", pair_number,
              name.substr(0, 36).c_str(), row.method.c_str(), row.repeat, fmt(row.t_err).c_str(),
              fmt(row.r_err_sum).c_str(), fmt(row.r_err_geo_deg).c_str(),
              fmt(row.build_ms + row.align_ms, 4).c_str(), row.iterations, row.points,
              row.converged ? "yes" : "no");
  std::fflush(stdout);
}

// The registrations of a bench run: one task per (pair, repeat, method), in this order: methods
// alternate within a repeat, so that machine noise spreads over all of them. Rows are printed
// (and written to the CSV) in task order.
class BenchTasks {
 public:
  BenchTasks(const BenchOptions& o, const std::vector<MethodSpec>& methods,
             const std::optional<Perturbation>& perturbation, std::vector<Job> jobs, std::FILE* csv)
      : o_(o),
        methods_(methods),
        perturbation_(perturbation),
        jobs_(std::move(jobs)),
        csv_(csv),
        per_pair_(o.repeat * methods.size()),
        total_(jobs_.size() * per_pair_) {
    rows_.reserve(total_);
  }

  [[nodiscard]] std::size_t total() const { return total_; }
  [[nodiscard]] double elapsed_s() const {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  }

  // Runs every task on `threads` threads; the rows, in task order.
  const std::vector<Row>& run(std::size_t threads) {
    if (threads <= 1) {
      for (std::size_t task = 0; task < total_; ++task) emit(run_task(task), task);
    } else {
      run_parallel(threads);
    }
    return rows_;
  }

 private:
  // Clouds are read once, on first use, under a lock (the registrations run outside it).
  const PointCloud& cloud(const std::filesystem::path& path, const char* role) {
    const std::string key = path.lexically_normal().string();
    const std::lock_guard lock(cache_mutex_);
    auto it = cloud_cache_.find(key);
    if (it == cloud_cache_.end())
      it = cloud_cache_.emplace(key, load_cloud(key, role, false, o_.depth)).first;
    return it->second;  // std::map nodes never move
  }

  Row run_task(std::size_t task) {
    const std::size_t j = task / per_pair_;
    const std::size_t rep = (task % per_pair_) / methods_.size();
    const RegistrationPair& pair = jobs_[j].second;
    const PointCloud& source = cloud(pair.source, "source");
    const PointCloud& reference_cloud = cloud(pair.reference, "reference");
    const Eigen::Matrix4d T_init =
        perturbation_ ? perturbed(pair.T_reference_source_gt, *perturbation_, j * 1000003ULL + rep)
                      : Eigen::Matrix4d::Identity();
    MethodSpec m = methods_[task % methods_.size()];
    m.sgd.sampling.seed += rep;
    const MethodRun run = run_method(m, source, reference_cloud, T_init);
    return make_row(jobs_[j], m.name, rep, T_init, run);
  }

  void emit(Row row, std::size_t task) {
    print_row(row, task / per_pair_ + 1);
    if (csv_) write_csv_line(csv_, &row);
    rows_.push_back(std::move(row));
    const double elapsed = elapsed_s();
    if (elapsed > 3.0 || tty_) {
      std::fprintf(stderr, "[bench] %zu/%zu registrations, %.0f s elapsed\n", rows_.size(), total_,
                   elapsed);
    }
  }

  // Throughput mode: independent registrations on `threads` workers (each builds its own
  // KD-tree); rows are printed in task order as soon as they and all before them are done.
  void run_parallel(std::size_t threads) {
    std::vector<std::optional<Row>> done(total_);
    std::exception_ptr failure;
    std::atomic<std::size_t> next{0};
    std::mutex done_mutex;
    std::condition_variable ready;
    const auto worker = [&] {
      for (std::size_t task = next++; task < total_; task = next++) {
        std::optional<Row> row;
        std::exception_ptr error;
        try {
          row = run_task(task);
        } catch (...) {
          error = std::current_exception();
        }
        const std::lock_guard lock(done_mutex);
        if (error && !failure) failure = error;
        if (error) next = total_;  // stop handing out tasks
        done[task] = std::move(row);
        ready.notify_one();
      }
    };
    std::vector<std::jthread> pool;
    for (std::size_t t = 0; t < threads; ++t) pool.emplace_back(worker);
    for (std::size_t task = 0; task < total_; ++task) {
      std::unique_lock lock(done_mutex);
      ready.wait(lock, [&] { return done[task].has_value() || failure; });
      if (!done[task]) break;
      Row row = std::move(*done[task]);
      lock.unlock();
      emit(std::move(row), task);
    }
    pool.clear();  // joins
    if (failure) std::rethrow_exception(failure);
  }

  const BenchOptions& o_;
  const std::vector<MethodSpec>& methods_;
  const std::optional<Perturbation>& perturbation_;
  const std::vector<Job> jobs_;
  std::FILE* const csv_;
  const std::size_t per_pair_;
  const std::size_t total_;
  const bool tty_ = isatty(STDERR_FILENO) != 0;
  const std::chrono::steady_clock::time_point t0_ = std::chrono::steady_clock::now();
  std::mutex cache_mutex_;
  std::map<std::string, PointCloud> cloud_cache_;
  std::vector<Row> rows_;
};

// What the small-source rules change of these settings (settings.hpp), for the summary line.
std::string small_source_note(const SgdSettings& s) {
  std::vector<std::string> rules;
  if (s.adapt_small_sources) rules.emplace_back("m capped");
  // optimizer_for a source of no points: the small-source rule's step, if it takes one.
  if (optimizer_for(s, 0).type != s.optimizer.type) rules.emplace_back("Gauss-Newton coarse steps");
  if (rules.empty()) return "";
  return " (small sources: " + (rules.size() == 2 ? rules[0] + ", " + rules[1] : rules[0]) + ")";
}

// One summary per method, in the order of --method.
void print_method_summaries(const std::vector<MethodSpec>& methods, const std::vector<Row>& rows,
                            const std::string& preset, const std::vector<Threshold>& thresholds) {
  for (const MethodSpec& m : methods) {
    std::vector<const Row*> mine;
    for (const auto& r : rows) {
      if (r.method == m.name) mine.push_back(&r);
    }
    std::string label = "method " + m.name;
    if (m.stochastic) {
      label += ", " + preset + " settings, optimizer " +
               std::string(to_string(m.sgd.optimizer.type)) +
               ", m = " + std::to_string(m.sgd.sampling.batch_size) + small_source_note(m.sgd);
    }
    print_summary(label, mine, thresholds);
  }
}

void run(const BenchOptions& o) {
  if (o.repeat == 0) throw InvalidSettingsError("--repeat must be at least 1");
  const std::vector<std::string> method_list = split_commas(o.settings.method);
  const std::vector<MethodSpec> methods = make_methods(method_list, o.settings);
  const std::optional<Perturbation> perturbation = parse_perturbation(o.perturb);
  const std::vector<Threshold> thresholds = parse_thresholds(o.success);
  std::vector<Job> jobs = read_jobs(o.pairs_files);
  const CsvFile csv = open_csv(o.csv);

  BenchTasks tasks(o, methods, perturbation, std::move(jobs), csv.get());
  print_row_header();
  const std::size_t threads = std::min(o.jobs, std::max<std::size_t>(tasks.total(), 1));
  const std::vector<Row>& rows = tasks.run(threads);
  const double wall_s = tasks.elapsed_s();

  print_method_summaries(methods, rows, o.settings.preset, thresholds);
  if (methods.size() > 1) print_comparison(method_list, rows, thresholds);
  std::printf(
      "\nthroughput: %zu registrations in %s s wall time on %zu thread(s) = %s per second "
      "(file reading included)\n",
      rows.size(), fmt(wall_s, 3).c_str(), threads,
      fmt(static_cast<double>(rows.size()) / wall_s, 3).c_str());
}

}  // namespace

void add_bench_command(CLI::App& app) {
  auto o = std::make_shared<BenchOptions>();
  CLI::App* cmd = app.add_subcommand(
      "bench",
      "Register every pair of one or more pairs files (format: PAIRS.md of the data folder, "
      "../shared/data/PAIRS.md beside the repository) and print "
      "per-pair errors and times and a summary. Time = preparation (kd-tree build, normals/"
      "covariances, downsampling) + registration; file I/O is excluded.");
  cmd->add_option("PAIRS_FILE", o->pairs_files, "Pairs file(s)")->required();
  cmd->add_option("--perturb", o->perturb,
                  "Start each pair from the ground truth composed with a random perturbation of "
                  "exactly TRANS_M metres and ROT_RAD radians (geodesic), seeded: "
                  "TRANS_M,ROT_RAD[,SEED] [default: start from identity]");
  cmd->add_option("--repeat", o->repeat,
                  "Registrations per pair; repeat r uses seed + r (and its own perturbation) "
                  "[default: 1]");
  cmd->add_option("-j,--jobs", o->jobs,
                  "Registrations run in parallel, each on its own thread with its own KD-tree "
                  "(throughput; the per-registration times then include contention for cores "
                  "and memory bandwidth; --threads is the threads of each registration). Rows "
                  "are still printed in pair order [default: 1]")
      ->check(CLI::Range(std::size_t{1}, std::size_t{256}));
  cmd->add_option("--csv", o->csv, "Write one CSV row per registration to this file");
  cmd->add_option("--success", o->success,
                  "Success threshold TRANS_M,ROT_DEG (translation error and geodesic rotation "
                  "error both below); repeat the option for several [default: 0.05,1 and 2,5]")
      ->take_all();
  add_depth_options(*cmd, o->depth);
  add_method_options(*cmd, o->settings, true);
  add_settings_options(*cmd, o->settings);
  // What a user of the command sets; every other option is in --help-all.
  static constexpr std::array<CommonOption, 12> kCommon{
      {{"perturb", "Start from the ground truth moved by TRANS_M,ROT_RAD[,SEED]"},
       {"repeat", ""},
       {"jobs", "Registrations run in parallel (throughput)"},
       {"csv", ""},
       {"success", "Success thresholds TRANS_M,ROT_DEG (repeat for several)"},
       {"method", "Methods, separated by commas: sgd, sgd-point, sgd-plane, sgd-gicp, icp, ..."},
       kPresetBrief,
       kGridBrief,
       kMaxDistanceBrief,
       {"threads", "Threads of each registration, 0 = every core (same result)"},
       {"seed", "Seed of the mini-batch sampler; repeat r uses seed + r"},
       kIntrinsicsBrief}};
  arrange_help(*cmd, kCommon);
  cmd->callback([o] { run(*o); });
}

}  // namespace sgdicp::cli
