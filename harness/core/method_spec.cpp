#include "harness/core/method_spec.hpp"

#include "harness/util/errors.hpp"
#include "harness/util/key_value.hpp"

namespace bvhbench {

MethodSpec parse_method_spec(const std::string& text) {
  MethodSpec spec;
  spec.text = text;
  const auto colon = text.find(':');
  spec.name = text.substr(0, colon);
  if (spec.name.empty()) throw InputError("method spec '" + text + "': empty method name");
  if (colon == std::string::npos) return spec;
  const std::string rest = text.substr(colon + 1);
  std::size_t pos = 0;
  while (pos <= rest.size()) {
    const std::size_t comma = rest.find(',', pos);
    const std::string pair = rest.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    if (!pair.empty()) add_key_value(pair, "method spec '" + text + "'", spec.given);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  return spec;
}

}  // namespace bvhbench
