#include "json_input.hpp"

#include "errors.hpp"

namespace bvhbench {

nlohmann::json parse_json_input(std::string_view text, const std::string& name) {
  using json = nlohmann::json;
  // The parser calls back on every value with its depth; the InputError thrown there leaves the
  // parser as it is (only json::exception is turned into "malformed JSON" below).
  const json::parser_callback_t limit_depth = [&](int depth, json::parse_event_t event, json&) {
    if ((event == json::parse_event_t::object_start || event == json::parse_event_t::array_start) &&
        depth >= kMaxJsonDepth)
      throw file_error(name, "JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
    return true;
  };
  try {
    return json::parse(text, limit_depth);
  } catch (const json::exception& e) {
    throw file_error(name, std::string("malformed JSON: ") + e.what());
  }
}

}  // namespace bvhbench
