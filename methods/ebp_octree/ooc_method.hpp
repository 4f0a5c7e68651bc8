#pragma once
/// The out-of-core variant of the ebp_octree method, `ebp_octree:store=M.ebp` (ooc_method.cpp):
/// answers from a store built by `bvhbench ebp build` through a page cache (OUT_OF_CORE.md). The
/// method's registration (ebp_method.cpp) creates it when `store` is given.
#include <memory>

#include "harness/core/method.hpp"
#include "harness/core/params.hpp"

namespace bvhbench {

/// p: the ebp_octree method's parameters, `store` non-empty (cache_mb, cold, coherent used).
std::unique_ptr<Method> make_ebp_ooc_method(const Params& p);

}  // namespace bvhbench
