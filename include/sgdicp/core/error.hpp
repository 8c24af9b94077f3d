#pragma once
// Typed errors thrown by the library. Every message names the problem (and the file and
// position where it applies) so the CLI can print it as is.
#include <stdexcept>
#include <string>

namespace sgdicp {

/// Base class of every error the library throws on purpose.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file could not be opened, read or written (missing, unreadable, I/O failure).
class IoError : public Error {
 public:
  using Error::Error;
};

/// A file was read but its content is not a valid instance of its format
/// (truncated, malformed header, wrong counts, unsupported field layout).
class FormatError : public Error {
 public:
  using Error::Error;
};

/// Settings that are out of range or contradict each other (e.g. a zero batch size).
class InvalidSettingsError : public Error {
 public:
  using Error::Error;
};

/// Input data the method cannot work with: empty clouds, fewer points than a mini-batch,
/// non-finite values in an initial transform, a non-rigid initial transform.
class InvalidInputError : public Error {
 public:
  using Error::Error;
};

}  // namespace sgdicp
