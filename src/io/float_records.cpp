// Headerless float32 records: KITTI .bin (x y z intensity) and .f32 (x y z).
#include "io/io_internal.hpp"

namespace sgdicp::io_detail {

void read_float_records(const std::string& name, std::string_view data, std::size_t floats,
                        const std::string& layout, PointSink& sink) {
  const std::size_t record = floats * sizeof(float);
  if (data.size() % record != 0) {
    fail_byte(name, data.size() - data.size() % record,
              "truncated record: file size " + std::to_string(data.size()) +
                  " bytes is not a multiple of " + std::to_string(record) + " (" + layout + ")");
  }
  const std::size_t n = data.size() / record;
  if (beyond_cloud_limit(n)) fail_byte(name, 0, cloud_limit_text(n));
  sink.result().points_in_file = n;
  sink.reserve(n, n);
  for (std::size_t i = 0; i < n; ++i) {
    const char* const p = data.data() + i * record;
    sink.add(load<float>(p, false), load<float>(p + 4, false), load<float>(p + 8, false));
  }
}

}  // namespace sgdicp::io_detail
