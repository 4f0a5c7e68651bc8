#pragma once
/// Answering a whole query set per call: what a Python method does with `batch=true` (one call
/// on the arrays, as a Python caller would make it), and no other method. A method that can is
/// a Method and a BatchAnswers; the harness asks for it with dynamic_cast once per job, so the
/// Method interface every other method implements carries none of it.
///
/// Its answers_in_batches() on: the harness calls inside_batch()/distance_batch() instead of
/// inside()/distance(), times whole-set calls, and records no per-query latency (one call answers
/// every query, so no query has a latency of its own). It declares no concurrent queries.
#include <cstdint>
#include <vector>

#include "harness/core/method.hpp"

namespace bvhbench {

class BatchAnswers {
 public:
  virtual ~BatchAnswers() = default;
  /// Whether this instance (with its options) answers in batches.
  virtual bool answers_in_batches() const = 0;
  /// Every point of `points`, in order: `inside` gets points.size() bytes (1 inside, 0 outside).
  virtual void inside_batch(const std::vector<Vec3d>& points, std::vector<std::uint8_t>& inside) = 0;
  /// Every point of `points`, in order: `out` gets points.size() answers.
  virtual void distance_batch(const std::vector<Vec3d>& points, std::vector<DistanceResult>& out) = 0;
};

/// `method` as a batch answerer, when it is one and answers in batches with its options; else null.
inline BatchAnswers* batch_answers(Method& method) {
  auto* b = dynamic_cast<BatchAnswers*>(&method);
  return b && b->answers_in_batches() ? b : nullptr;
}

}  // namespace bvhbench
