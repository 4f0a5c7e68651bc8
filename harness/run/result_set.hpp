#pragma once
/// A set of result files as `compare` reads it: a folder's runs/*.json (or *.json), or one file,
/// each checked against the result schema (result_schema.hpp).
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// Result files read from a folder (`DIR/runs/*.json`, else `DIR/*.json`) or one file.
struct ResultSet {
  std::string path;
  std::vector<std::string> files;          ///< one per result, same order
  std::vector<nlohmann::json> results;
};

/// Reads and validates a result set. Throws InputError (exit 2) for a missing or empty folder,
/// an unreadable file, malformed JSON, or a file that is not a bvhbench result.
ResultSet load_result_set(const std::string& path);
/// Parses and validates the text of one result file (`file` names it in messages), as
/// load_result_set does for each (option values of older results read canonical: "1.0" as "1").
/// Throws InputError: malformed JSON, not a bvhbench result.
nlohmann::json parse_result(const std::string& text, const std::string& file);

}  // namespace bvhbench
