// fault: a testing-only method that fails on purpose, so that tests can check that a suite
// turns a crash, a hang, a blow-up or an exception into a status row and goes on.
// Listed by `bvhbench methods --all` only.
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <sys/resource.h>
#include <thread>
#include <unistd.h>
#include <vector>

#include "harness/core/mesh.hpp"
#include "harness/core/registry.hpp"

namespace bvhbench {
namespace {

class Fault final : public Method {
 public:
  explicit Fault(const Params& p) : mode_(p.get("mode")), at_(p.get("at")) {}

  void build(const Mesh& mesh, const BuildContext&) override {
    n_ = mesh.num_triangles();
    ++builds_in_process;
    if (at_ == "build") trigger();
  }
  /// Which process built it and how many builds that process made: a suite's tests check that
  /// the jobs of one structure share one build (one process, one build).
  nlohmann::json info() const override { return {{"pid", long(getpid())}, {"builds_in_process", builds_in_process}}; }
  bool inside(const Vec3d& p) override {
    if (at_ == "query") trigger();
    return p.x < 0;
  }
  DistanceResult distance(const Vec3d& p) override {
    if (at_ == "query") trigger();
    DistanceResult r;
    r.distance = p.x;
    return r;
  }
  std::size_t structure_bytes() const override { return sizeof(*this); }

 private:
  void trigger() {
    if (mode_ == "crash") {
      std::raise(SIGSEGV);
    } else if (mode_ == "abort") {
      std::abort();
    } else if (mode_ == "hang") {
      for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
    } else if (mode_ == "oom") {
      // Grow until the allocator fails (the suite's address-space limit) or the OS says no.
      // Under an address-space limit the allocation itself fails, so the memory is not touched:
      // filling gigabytes only makes the job slow enough on a loaded machine to end as a timeout
      // instead. Without a limit, only touched memory runs the machine out of it.
      rlimit as{};
      const bool limited = getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY;
      std::vector<char*> blocks;
      for (;;) {
        char* b = new char[256 << 20];
        if (limited) static_cast<volatile char*>(b)[0] = 1;  // one page: the allocation is observable
        else std::memset(b, 1, 256 << 20);
        blocks.push_back(b);
      }
    } else if (mode_ == "throw") {
      throw std::runtime_error("fault: deliberate exception");
    }
  }
  std::string mode_, at_;
  std::size_t n_ = 0;
  static inline int builds_in_process = 0;
};

}  // namespace
}  // namespace bvhbench

void bvhbench_register_fault(bvhbench::Registry& r) {
  using namespace bvhbench;
  MethodInfo m = MethodInfo::named("fault",
                                   "Testing only: fails on purpose (crash, abort, hang, oom, throw) to test job isolation");
  // Capabilities, said once here (false unless set).
  m.caps.inside = true; m.caps.distance = true;
  m.params = {{"mode", ParamType::choice, ParamRole::query, "none", "what goes wrong", {"none", "crash", "abort", "hang", "oom", "throw"}},
              {"at", ParamType::choice, ParamRole::query, "query", "when it goes wrong", {"build", "query"}}};
  m.create = [](const Params& p) { return std::make_unique<Fault>(p); };
  m.testing_only = true;
  r.add(std::move(m));
}
