#pragma once
/// The EBP-Octree's build options (the table kBuildOptions, core/build_params.hpp) as the
/// harness's typed options: their declarations, the BuildParams a job or `ebp build` resolves to,
/// and the texts and JSON a record shows of a built structure's options.
#include <map>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "harness/core/params.hpp"
#include "methods/ebp_octree/core/build_params.hpp"

namespace bvhbench {

/// One ParamSpec (ParamRole::build) per build option, in the table's order.
std::vector<ParamSpec> build_option_specs();

/// The build options' names in the table's order, ", "-separated (listings and messages).
std::string build_option_names();

/// Whether `name` is a build option of the table.
bool is_build_option(const std::string& name);

/// The build parameters among the method's resolved parameters `p`, with `threads` build threads.
ebp::BuildParams build_params(const Params& p, int threads);

/// Each build option of `bp` as the canonical text its declaration reads (a store's own options,
/// recorded in place of the job's).
std::map<std::string, std::string> build_option_texts(const ebp::BuildParams& bp);

/// Each build option of `bp` as a JSON number (`ebp info`).
nlohmann::json build_option_json(const ebp::BuildParams& bp);

}  // namespace bvhbench
