// The build options' table as the harness's typed options (build_option_params.hpp).
#include "methods/ebp_octree/build_option_params.hpp"

namespace bvhbench {
namespace {

ParamType param_type(const ebp::BuildOption& o) {
  return o.type == ebp::BuildOption::Type::real ? ParamType::real : ParamType::integer;
}

/// `v` as the canonical text of option `o` (5.0 -> "5", as a typed value prints).
std::string canonical_text(const ebp::BuildOption& o, double v) {
  ParamValue x;
  x.type = param_type(o);
  x.real = v;
  x.integer = std::int64_t(v);
  return x.canonical();
}

}  // namespace

std::vector<ParamSpec> build_option_specs() {
  std::vector<ParamSpec> specs;
  for (const ebp::BuildOption& o : ebp::kBuildOptions)
    specs.push_back({o.name, param_type(o), ParamRole::build, canonical_text(o, o.default_value()), o.help, {}, o.min,
                     o.max});
  return specs;
}

std::string build_option_names() {
  std::string names;
  for (const ebp::BuildOption& o : ebp::kBuildOptions) names += (names.empty() ? "" : ", ") + std::string(o.name);
  return names;
}

bool is_build_option(const std::string& name) {
  for (const ebp::BuildOption& o : ebp::kBuildOptions)
    if (name == o.name) return true;
  return false;
}

ebp::BuildParams build_params(const Params& p, int threads) {
  ebp::BuildParams bp;
  for (const ebp::BuildOption& o : ebp::kBuildOptions)
    o.set(bp, o.type == ebp::BuildOption::Type::real ? p.get_real(o.name) : double(p.get_int(o.name)));
  bp.threads = threads;
  return bp;
}

std::map<std::string, std::string> build_option_texts(const ebp::BuildParams& bp) {
  std::map<std::string, std::string> texts;
  for (const ebp::BuildOption& o : ebp::kBuildOptions) texts[o.name] = canonical_text(o, o.get(bp));
  return texts;
}

nlohmann::json build_option_json(const ebp::BuildParams& bp) {
  nlohmann::json j = nlohmann::json::object();
  for (const ebp::BuildOption& o : ebp::kBuildOptions)
    j[o.name] = o.type == ebp::BuildOption::Type::real ? nlohmann::json(o.get(bp)) : nlohmann::json(int(o.get(bp)));
  return j;
}

}  // namespace bvhbench
