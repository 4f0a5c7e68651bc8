#pragma once
/// The contract every fuzz target checks (fuzz/README.md): a reader given any bytes either
/// accepts them or refuses them with a bvhbench::InputError whose message is printable (valid
/// UTF-8 without control characters but tab and newline: `printable(msg) == msg`) and names the
/// input. Anything else is a finding: a crash, a sanitizer report, a hang, a leak, an allocation
/// beyond -malloc_limit_mb, or an exception of another type, which escapes the target (libFuzzer
/// reports it as a crash, the replay driver as a failed input).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "errors.hpp"
#include "printable.hpp"

namespace bvhbench::fuzz {

/// A broken promise: says which and aborts, so that libFuzzer keeps the input as a crash.
[[noreturn]] inline void violated(const std::string& what) {
  std::fprintf(stderr, "fuzz contract violated: %s\n", printable(what).c_str());
  std::fflush(stderr);
  std::abort();
}

inline void check(bool ok, const std::string& what) {
  if (!ok) violated(what);
}

/// A refusal's message: printable, and naming `name` (as printable() writes it).
inline void check_message(const std::string& message, const std::string& name) {
  check(printable(message) == message, "message is not printable: " + message);
  check(message.find(printable(name)) != std::string::npos, "message does not name '" + name + "': " + message);
}

/// Runs `read()`: nothing if it returns, the message if it refuses with an InputError (checked
/// with check_message). Any other exception propagates.
template <class Read>
std::optional<std::string> refusal(const std::string& name, Read&& read) {
  try {
    read();
    return std::nullopt;
  } catch (const InputError& e) {
    check_message(e.what(), name);
    return std::string(e.what());
  }
}

/// Runs `read()`: true if it returns, false if it refuses (see refusal()).
template <class Read>
bool accepts(const std::string& name, Read&& read) {
  return !refusal(name, std::forward<Read>(read));
}

inline std::string_view as_text(const std::uint8_t* data, std::size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

}  // namespace bvhbench::fuzz
