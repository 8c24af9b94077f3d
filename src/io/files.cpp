// Whole files in and out: the one bounded way the readers read a file (files.hpp) and the
// writers write one.
#include "io/io_internal.hpp"

namespace sgdicp {
namespace {

namespace fs = std::filesystem;
using io_detail::system_message;

struct FileCloser {
  void operator()(std::FILE* file) const noexcept { std::fclose(file); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;

// Only regular files: a device or FIFO has no size to check, and /dev/zero never ends.
void check_regular_file(const fs::path& path, const std::string& name) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (ec || status.type() == fs::file_type::regular) return;  // missing: fopen says why
  if (status.type() == fs::file_type::directory) {
    throw IoError(name + ": cannot read: " + system_message(EISDIR));
  }
  const char* kind = status.type() == fs::file_type::character ? "a character device"
                     : status.type() == fs::file_type::block   ? "a block device"
                     : status.type() == fs::file_type::fifo    ? "a FIFO"
                     : status.type() == fs::file_type::socket  ? "a socket"
                                                               : "not a regular file";
  throw IoError(name + ": " + kind +
                " (only regular files are read, so that their size bounds what is read)");
}

}  // namespace

std::string limit_text(std::uint64_t bytes) {
  return std::to_string(bytes) + " bytes = " + std::to_string(bytes >> 30) + " GiB";
}

std::vector<char> read_whole_file(const fs::path& path, const std::string& name) {
  check_regular_file(path, name);
  errno = 0;
  const FilePtr file(std::fopen(path.string().c_str(), "rb"));
  if (!file) throw IoError(name + ": cannot open: " + system_message(errno));
  std::error_code size_error;
  const auto expected = fs::file_size(path, size_error);
  if (size_error) throw IoError(name + ": cannot read the size: " + size_error.message());
  const auto too_large = [&]() {
    return IoError(name + ": larger than the largest file read (" + limit_text(kMaxFileBytes) +
                   ")");
  };
  if (expected > kMaxFileBytes) throw too_large();
  // One byte more than expected so that the end of file is seen by the first read; a file that
  // grows while it is read is still bounded by kMaxFileBytes.
  std::vector<char> bytes(static_cast<std::size_t>(expected) + 1);
  std::size_t used = 0;
  for (;;) {
    if (used == bytes.size()) {
      if (used > kMaxFileBytes) throw too_large();
      bytes.resize(std::min<std::size_t>(bytes.size() * 2, kMaxFileBytes + 1));
    }
    errno = 0;
    const std::size_t got = std::fread(bytes.data() + used, 1, bytes.size() - used, file.get());
    used += got;
    if (std::ferror(file.get()) != 0) {
      throw IoError(name + ": cannot read: " + system_message(errno));
    }
    if (got == 0) break;
  }
  bytes.resize(used);
  return bytes;
}

}  // namespace sgdicp

namespace sgdicp::io_detail {

void write_whole_file(const fs::path& path, const std::string& name, std::string_view data) {
  errno = 0;
  FilePtr file(std::fopen(path.string().c_str(), "wb"));
  if (!file) throw IoError(name + ": cannot open for writing: " + system_message(errno));
  errno = 0;
  if (std::fwrite(data.data(), 1, data.size(), file.get()) != data.size()) {
    throw IoError(name + ": cannot write: " + system_message(errno));
  }
  // fclose flushes, so its failure (e.g. a full disk) is a write failure too.
  errno = 0;
  if (std::fclose(file.release()) != 0) {
    throw IoError(name + ": cannot write: " + system_message(errno));
  }
}

}  // namespace sgdicp::io_detail
