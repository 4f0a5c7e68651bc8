#pragma once
/// The out-of-core variant of the ebp_octree method, `ebp_octree:store=M.ebp` (ooc_method.cpp):
/// answers from a store built by `bvhbench ebp build` through a page cache (OUT_OF_CORE.md). The
/// method's registration (ebp_method.cpp) creates it when `store` is given.
#include <memory>
#include <vector>

#include "harness/core/method.hpp"
#include "harness/core/params.hpp"

namespace bvhbench {

/// The out-of-core options of the ebp_octree method: `store` (the file that makes a job out of
/// core) and its page cache's.
std::vector<ParamSpec> ooc_params();

/// Whether the method's parameters `p` name a store (the one place `store` tells the two variants
/// apart).
bool is_out_of_core(const Params& p);

/// The method's check (MethodInfo::check): beside a store, no build option (the store carries its
/// own, which a result records); without one, no option of the store's page cache. InputError.
void check_ooc_options(const Params& p);

/// p: the ebp_octree method's parameters, `store` non-empty (cache_mb, cold, coherent used).
std::unique_ptr<Method> make_ebp_ooc_method(const Params& p);

}  // namespace bvhbench
