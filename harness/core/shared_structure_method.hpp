#pragma once
/// A Method whose queries may run concurrently (method.hpp, "Threads"), written the one way that
/// makes that safe: the built structure is shared and read-only while queries run, and whatever a
/// query writes (path state, counters, scratch) lives in a State, one per thread.
///
/// The method's own queries (thread 0, or a single-threaded job) go to a State of its own, made
/// by start_queries() at the end of build(); new_query_state() makes one more for another thread.
/// So a single thread and T threads run the same code, and answer and count alike.
#include <memory>
#include <stdexcept>
#include <vector>

#include "harness/core/method.hpp"

namespace bvhbench {

/// State: a QueryState (declare it `final`, so the forwarding below is a direct call) that reads
/// the method's structure through a const reference or pointer.
template <class State>
class SharedStructureMethod : public Method {
 public:
  bool inside(const Vec3d& p) override { return own().inside(p); }
  DistanceResult distance(const Vec3d& p) override { return own().distance(p); }
  void reset_path() override {
    if (own_) own_->reset_path();
  }
  std::vector<Counter> counters() const override { return own_ ? own_->counters() : std::vector<Counter>{}; }
  void reset_counters() override {
    if (own_) own_->reset_counters();
  }
  std::unique_ptr<QueryState> new_query_state() const override { return own_ ? make_state() : nullptr; }

 protected:
  /// A fresh State over the built structure (only called after build()).
  virtual std::unique_ptr<State> make_state() const = 0;
  /// Ends build(): the method's own State.
  void start_queries() { own_ = make_state(); }
  /// The method's own State (null before build()).
  const State* own_state() const { return own_.get(); }

 private:
  State& own() {
    if (!own_) throw std::logic_error("a query before build()");
    return *own_;
  }
  std::unique_ptr<State> own_;
};

}  // namespace bvhbench
