#pragma once
/// A fixed reference kernel timed in the same process as a job's queries, so that `compare`
/// can tell a slower or busier machine from a slower method: throughput × kernel seconds is
/// (to first order) independent of the machine's speed.
#include <cstdint>
#include <vector>

#include <nlohmann/json.hpp>

namespace bvhbench {

/// Version of the kernel below. Calibrations of different kernels are not comparable; compare
/// falls back to raw throughput (and says so) when the two sides disagree.
inline constexpr const char* kCalibrationKernel = "chase_fp/1";

/// Runs the reference kernel once and returns its checksum (the same on every machine: the
/// kernel's work is fixed, never adapted to the time it takes).
///
/// The kernel mimics a spatial query loop: a dependent pointer chase over `nodes` nodes of
/// 32 bytes laid out in a random cycle (a tree walk's cache misses), with a point-to-box
/// distance in floating point at each node (the traversal's arithmetic). `steps` node visits.
double calibration_kernel(std::uint32_t nodes, std::uint32_t steps);

/// The result's `calibration` block: the kernel timed `samples` times after a short untimed
/// warm-up, each run ~20 ms on a quiet 2020s core; on a crowded machine sampling stops after
/// 3 samples once 1 s went into it (the kernel's work per sample never changes).
/// {"kernel": "chase_fp/1", "nodes": .., "steps": .., "working_set_bytes": ..,
///  "kernel_seconds": [..samples..], "median_seconds": .., "min_seconds": .., "checksum": ..}
nlohmann::json measure_calibration(int samples = 5);

}  // namespace bvhbench
