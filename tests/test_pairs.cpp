// Tests of the pairs-file reader (pairs.hpp, format: shared/data/PAIRS.md).
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

#include <gtest/gtest.h>

#include "sgdicp/core/error.hpp"
#include "sgdicp/core/pose.hpp"
#include "sgdicp/tools/pairs.hpp"
#include "test_support.hpp"

namespace {

using sgdicp::test::TempDir;

namespace fs = std::filesystem;

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  ASSERT_TRUE(out.good()) << path;
}

const char* const kIdentity12 = "1 0 0 0 0 1 0 0 0 0 1 0";

// The message of the FormatError thrown by read_pairs_file(path), or "" (and a failure).
std::string format_error_of(const fs::path& path) {
  try {
    (void)sgdicp::read_pairs_file(path);
    ADD_FAILURE() << "no FormatError for " << path;
  } catch (const sgdicp::FormatError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "wrong exception type for " << path << ": " << e.what();
  }
  return {};
}

TEST(PairsFile, SharedPairsFilesAreValid) {
  const fs::path folder = fs::path(SGDICP_SHARED_DATA) / "pairs";
  if (!fs::is_directory(folder)) GTEST_SKIP() << folder << " is absent";
  std::vector<fs::path> files;
  for (const auto& entry : fs::directory_iterator(folder)) {
    if (entry.path().extension() == ".txt") files.push_back(entry.path());
  }
  std::sort(files.begin(), files.end());
  ASSERT_FALSE(files.empty());
  for (const auto& file : files) {
    SCOPED_TRACE(file.string());
    // Independent count of the pair lines: not blank, not starting with '#'.
    std::ifstream in(file);
    std::string line;
    std::vector<std::size_t> pair_lines;
    std::size_t number = 0;
    while (std::getline(in, line)) {
      ++number;
      const auto first = line.find_first_not_of(" \t\r");
      if (first != std::string::npos && line[first] != '#') pair_lines.push_back(number);
    }
    const auto pairs = sgdicp::read_pairs_file(file);
    ASSERT_EQ(pairs.size(), pair_lines.size());
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      const auto& p = pairs[i];
      EXPECT_EQ(p.line, pair_lines[i]);
      EXPECT_TRUE(fs::is_regular_file(p.source)) << p.source << " (line " << p.line << ")";
      EXPECT_TRUE(fs::is_regular_file(p.reference)) << p.reference << " (line " << p.line << ")";
      EXPECT_GT(fs::file_size(p.source), 0U) << p.source;
      EXPECT_GT(fs::file_size(p.reference), 0U) << p.reference;
      // Resolved against the pairs file's folder.
      EXPECT_EQ(fs::weakly_canonical(p.source).string().rfind(
                    fs::weakly_canonical(folder.parent_path()).string(), 0),
                0U)
          << p.source;
      EXPECT_TRUE(sgdicp::is_rigid_transform(p.T_reference_source_gt, 1e-12))
          << p.T_reference_source_gt;
    }
  }
}

TEST(PairsFile, ParsesFieldsAndResolvesRelativePaths) {
  const TempDir dir;
  fs::create_directories(dir.path() / "lists");
  const fs::path file = dir.path() / "lists" / "pairs.txt";
  write_file(file,
             "a.pcd ../clouds/b.pcd 0 -1 0 1  1 0 0 2  0 0 1 3\n"
             "sub/c.bin /abs/d.bin " +
                 std::string(kIdentity12) + "\n");
  const auto pairs = sgdicp::read_pairs_file(file);
  ASSERT_EQ(pairs.size(), 2U);
  EXPECT_EQ(pairs[0].source.lexically_normal(),
            (dir.path() / "lists" / "a.pcd").lexically_normal());
  EXPECT_EQ(pairs[0].reference.lexically_normal(),
            (dir.path() / "clouds" / "b.pcd").lexically_normal());
  EXPECT_EQ(pairs[1].source.lexically_normal(),
            (dir.path() / "lists" / "sub" / "c.bin").lexically_normal());
  EXPECT_EQ(pairs[1].reference, fs::path("/abs/d.bin")) << "absolute paths stay as they are";
  Eigen::Matrix4d expected;
  expected << 0, -1, 0, 1, 1, 0, 0, 2, 0, 0, 1, 3, 0, 0, 0, 1;
  EXPECT_LT((pairs[0].T_reference_source_gt - expected).cwiseAbs().maxCoeff(), 1e-15);
  EXPECT_EQ(pairs[1].T_reference_source_gt, Eigen::Matrix4d::Identity());
  EXPECT_EQ(pairs[0].line, 1U);
  EXPECT_EQ(pairs[1].line, 2U);
}

TEST(PairsFile, RelativePairsFilePath) {
  // A pairs file given by a bare file name: its folder is the current directory.
  const TempDir dir;
  write_file(dir.path() / "p.txt", "s.xyz r.xyz " + std::string(kIdentity12) + "\n");
  const fs::path cwd = fs::current_path();
  fs::current_path(dir.path());
  std::vector<sgdicp::RegistrationPair> pairs;
  EXPECT_NO_THROW(pairs = sgdicp::read_pairs_file("p.txt"));
  fs::current_path(cwd);
  ASSERT_EQ(pairs.size(), 1U);
  EXPECT_EQ(fs::absolute(dir.path() / pairs[0].source).lexically_normal(),
            (dir.path() / "s.xyz").lexically_normal());
}

TEST(PairsFile, CommentsAndBlankLinesAreSkipped) {
  const TempDir dir;
  const fs::path file = dir.path() / "pairs.txt";
  write_file(file,
             "# header comment 1 2 3\n"  // 1
             "\n"                        // 2
             "   \t  \n"                 // 3
             "   # indented comment\n"   // 4
             "s1.pcd r1.pcd " +          // 5
                 std::string(kIdentity12) +
                 "\r\n"               // Windows line end
                 "#s2.pcd r2.pcd " +  // 6: commented-out pair
                 std::string(kIdentity12) +
                 "\n"
                 "s3.pcd r3.pcd " +  // 7, no final newline
                 std::string(kIdentity12));
  const auto pairs = sgdicp::read_pairs_file(file);
  ASSERT_EQ(pairs.size(), 2U);
  EXPECT_EQ(pairs[0].line, 5U);
  EXPECT_EQ(pairs[0].source.filename(), "s1.pcd");
  EXPECT_EQ(pairs[0].reference.filename(), "r1.pcd");
  EXPECT_EQ(pairs[1].line, 7U);
  EXPECT_EQ(pairs[1].source.filename(), "s3.pcd");
}

TEST(PairsFile, BadLineNamesFileAndLine) {
  const TempDir dir;
  const fs::path file = dir.path() / "bad_pairs.txt";
  write_file(file,
             "# comment\n"
             "s1.pcd r1.pcd " +
                 std::string(kIdentity12) +
                 "\n"
                 "s2.pcd r2.pcd 1 0 0 0 0 1 0 0 0 0 1\n");  // line 3: 11 numbers
  const std::string message = format_error_of(file);
  EXPECT_NE(message.find(file.string()), std::string::npos) << message;
  EXPECT_NE(message.find("line 3"), std::string::npos) << message;
}

TEST(PairsFile, OtherBadLines) {
  const TempDir dir;
  const struct {
    const char* name;
    std::string line;
  } cases[] = {
      {"one_field", "only_a_source.pcd"},
      {"no_numbers", "s.pcd r.pcd"},
      {"thirteen", "s.pcd r.pcd 1 0 0 0 0 1 0 0 0 0 1 0 7"},
      {"word", "s.pcd r.pcd 1 0 0 0 0 1 0 0 0 0 1 zero"},
      {"non_rigid", "s.pcd r.pcd 2 0 0 0 0 2 0 0 0 0 2 0"},
      {"nan", "s.pcd r.pcd 1 0 0 nan 0 1 0 0 0 0 1 0"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const fs::path file = dir.path() / (std::string(c.name) + ".txt");
    write_file(file, "s0.pcd r0.pcd " + std::string(kIdentity12) + "\n\n" + c.line + "\n");
    const std::string message = format_error_of(file);
    EXPECT_NE(message.find(file.string()), std::string::npos) << message;
    EXPECT_NE(message.find("line 3"), std::string::npos) << message;
  }
}

TEST(PairsFile, EmptyFileIsAnError) {
  const TempDir dir;
  const fs::path empty = dir.path() / "empty.txt";
  write_file(empty, "");
  EXPECT_NE(format_error_of(empty).find(empty.string()), std::string::npos);
  const fs::path comments = dir.path() / "comments.txt";
  write_file(comments, "# nothing here\n\n   \n# still nothing\n");
  EXPECT_NE(format_error_of(comments).find(comments.string()), std::string::npos);
}

TEST(PairsFile, MissingFileIsAnIoError) {
  const TempDir dir;
  EXPECT_THROW((void)sgdicp::read_pairs_file(dir.path() / "missing.txt"), sgdicp::IoError);
}

TEST(PairsText, ParsesFromMemoryLikeTheFile) {
  // parse_pairs is what read_pairs_file runs on the file's text (and what the fuzz target calls).
  const std::string text = "# c\n\ns.pcd ../r.pcd " + std::string(kIdentity12) + "\r\nx y " +
                           std::string(kIdentity12);  // no final newline
  const auto pairs = sgdicp::parse_pairs(text, "/data/lists", "mem");
  ASSERT_EQ(pairs.size(), 2U);
  EXPECT_EQ(pairs[0].line, 3U);
  EXPECT_EQ(pairs[0].source, fs::path("/data/lists/s.pcd"));
  EXPECT_EQ(pairs[0].reference, fs::path("/data/lists/../r.pcd"));
  EXPECT_EQ(pairs[1].line, 4U);
  EXPECT_EQ(pairs[1].T_reference_source_gt, Eigen::Matrix4d::Identity());
  try {
    (void)sgdicp::parse_pairs("a b 1 2\n", "", "mem");
    ADD_FAILURE() << "no FormatError";
  } catch (const sgdicp::FormatError& e) {
    EXPECT_NE(std::string(e.what()).find("mem: line 1"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)sgdicp::parse_pairs("", "", "mem"), sgdicp::FormatError);
  // A NUL byte is an ordinary character of a line, not its end.
  EXPECT_THROW((void)sgdicp::parse_pairs(std::string("a\0b", 3), "", "mem"), sgdicp::FormatError);
}

}  // namespace
