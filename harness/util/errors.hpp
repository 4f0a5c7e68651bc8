#pragma once
/// Error kinds that cross the harness boundary. Each maps to a status and an exit code
/// (docs/architecture.md, "Contracts": exit codes): anything thrown inside a method or a reader is
/// caught in `run_job` / `main` and turned into a status row and a message, never a crash.
#include <stdexcept>
#include <string>

#include "harness/util/printable.hpp"

namespace bvhbench {

/// Bad input: a malformed file (mesh, query set, structure file) or a bad value given by the
/// user (unknown method or parameter, unparsable number). Exit code 2, status `rejected_input`.
/// The message names the file or value and the problem.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A method cannot answer this kind of query (status `unsupported`). Never faked.
struct UnsupportedError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Thrown by a command (the harness's or a method's, such as `bvhbench ebp verify`) to end the
/// program with this exit code after writing its outputs; main() returns it.
struct ExitCode {
  int code;
};

/// Formats "FILE: problem" the way every reader reports errors. Both parts go through
/// printable(): a path or a quoted token may hold bytes that are not UTF-8, and the message ends
/// up in a result JSON.
inline InputError file_error(const std::string& path, const std::string& problem) {
  return InputError(printable(path + ": " + problem));
}

}  // namespace bvhbench
