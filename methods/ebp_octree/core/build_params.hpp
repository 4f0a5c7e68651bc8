#pragma once
/// The parameters of the EBP-Octree's build (in memory: build/octree_build.hpp; external: build/external_build.hpp),
/// and the table of its build options, the one place each option is declared: its name, type,
/// default (BuildParams' initializer), range, help and where a store's header keeps it. The
/// method's typed options, `bvhbench ebp build/stats --param`, the store's header (written and
/// read), `ebp info`, the record of a store job and the guard against build options beside a
/// store all read this table (build_option_params.hpp turns it into the harness's options).
#include "methods/ebp_octree/core/octcode.hpp"

namespace ebp {

struct BuildParams {
  double leaf_factor = 5.0;     ///< leaf cell size >= leaf_factor x average edge length
  int max_planes = 8;           ///< bounding planes per node (at most)
  double cluster_angle = 30.0;  ///< degrees: normals closer than this share one plane
  int threads = 1;              ///< > 1: TBB parallel build (the job's threads, not an option of the structure)
  int max_level = kMaxLevel;    ///< clamp of the leaf level (1..19; tests only)
};

/// One build option: a field of BuildParams that shapes the structure, chosen by the user as
/// `ebp_octree:NAME=V` or `bvhbench ebp build --param NAME=V`, and kept in a store's header.
struct BuildOption {
  enum class Type { real, integer };
  const char* name;
  Type type;
  double BuildParams::*real_field;  ///< Type::real: the field; else null
  int BuildParams::*int_field;      ///< Type::integer: the field; else null
  double min, max;                  ///< inclusive range
  const char* help;
  /// Where a store's header keeps it: FileHeader::build_reals[header_slot] for a real,
  /// FileHeader::build_ints[header_slot] for an integer (store/format.hpp; the layout is fixed).
  int header_slot;

  double get(const BuildParams& p) const { return type == Type::real ? p.*real_field : double(p.*int_field); }
  void set(BuildParams& p, double v) const {
    if (type == Type::real)
      p.*real_field = v;
    else
      p.*int_field = int(v);
  }
  double default_value() const { return get(BuildParams{}); }
};

/// Every build option, in the order listings show them.
inline constexpr BuildOption kBuildOptions[] = {
    {"leaf_factor", BuildOption::Type::real, &BuildParams::leaf_factor, nullptr, 0.05, 1e6,
     "leaf cell size >= leaf_factor x average edge length (the paper: 5)", 0},
    {"max_planes", BuildOption::Type::integer, nullptr, &BuildParams::max_planes, 0, 64,
     "bounding planes per node, at most", 0},
    {"cluster_angle", BuildOption::Type::real, &BuildParams::cluster_angle, nullptr, 0.5, 90,
     "degrees: face normals closer than this share one bounding plane", 1},
};

}  // namespace ebp
