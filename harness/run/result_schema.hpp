#pragma once
/// The one description of a result file, run/result_schema.json (docs/results.md), compiled into
/// the runner. The writer is checked against it by the tests, `compare` validates what it reads
/// with it, summary.csv takes its columns from it, and the Python readers (plots/results_io.py)
/// read the same file, so that none of them can drift from the others without a test failing.
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// One described value: a dotted path in which "*" stands for any key of a free-form object.
struct ResultField {
  std::string path;      ///< e.g. "queries.throughput_qps.median", "counters.*"
  std::string type;      ///< string, integer, number, boolean, object, array<T>, any; "|null" allows null
  std::string required;  ///< always, ok (when status is ok), optional
  std::string doc;       ///< one line
  std::vector<std::string> values;  ///< a string's only values ("enum"); empty: any
};

/// One column of summary.csv: a field's value, the ratio of two fields, or the share a / (a + b).
struct SummaryColumn {
  std::string column;
  std::string field;       ///< the value shown (empty for ratio and share)
  std::string or_stem_of;  ///< when `field` is missing: the file-name stem of this path field
  std::string ratio_of[2];  ///< column = first / second
  std::string share_of[2];  ///< column = first / (first + second)
};

/// "a.b.c" -> {"a", "b", "c"}.
std::vector<std::string> split_field_path(const std::string& path);

class ResultSchema {
 public:
  /// The schema compiled into this build.
  static const ResultSchema& get();
  /// Parses a schema document (the layout of result_schema.json). Throws std::invalid_argument.
  static ResultSchema parse(std::string_view text);

  const std::string& version() const { return version_; }  ///< "bvhbench.result/1"
  const std::vector<ResultField>& fields() const { return fields_; }
  const std::vector<SummaryColumn>& summary_columns() const { return columns_; }
  /// The job statuses, in the schema's order (its `status` enum): the one list of them.
  const std::vector<std::string>& statuses() const;

  /// The field describing `path` (keys in order), or null: an exact entry first, else one with
  /// "*" in place of keys, else a free-form "any" ancestor.
  const ResultField* describe(const std::vector<std::string>& path) const;

  /// Throws bvhbench::InputError "FILE: <field> must be <type>" (or "... missing <field>", "not a
  /// bvhbench result", "unknown result schema") when `result` does not follow the schema: a
  /// value of another type, or a required field missing where its parent is present. Fields the
  /// schema does not describe are allowed (a newer writer may add them).
  void validate(const nlohmann::json& result, const std::string& file) const;

  /// Every value of `result` the schema does not describe, as dotted paths (for the writer's
  /// tests: a field added to the writer must be added to the schema too).
  std::vector<std::string> undescribed(const nlohmann::json& result) const;

 private:
  std::string version_;
  std::vector<ResultField> fields_;
  std::vector<SummaryColumn> columns_;
};

}  // namespace bvhbench
