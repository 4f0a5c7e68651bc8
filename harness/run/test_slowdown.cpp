#include "harness/run/test_slowdown.hpp"

#include <cstdint>
#include <cstdlib>
#include <iostream>

#include "harness/core/batch_answers.hpp"
#include "harness/util/errors.hpp"

namespace bvhbench {

namespace {

/// UNITS rounds of a dependent chain: each round needs the last, and the asm statement tells the
/// compiler the value is used, so neither the loop nor its length can be folded away.
inline void extra_work(std::uint64_t units) {
  std::uint64_t x = units;
  for (std::uint64_t i = 0; i < units; ++i) {
    x = x * 0x9E3779B97F4A7C15ull + i;
    asm volatile("" : "+r"(x));
  }
}

/// A QueryState's calls (Base: QueryState, or Method, which is one) forwarded to `inner`, with
/// extra_work() before every query: what the slowed method and each of its threads' states share.
template <class Base>
class SlowedQueries : public Base {
 public:
  SlowedQueries(QueryState& inner, std::uint64_t units) : queries_(inner), units_(units) {}
  bool inside(const Vec3d& p) override {
    extra_work(units_);
    return queries_.inside(p);
  }
  DistanceResult distance(const Vec3d& p) override {
    extra_work(units_);
    return queries_.distance(p);
  }
  void reset_path() override { queries_.reset_path(); }
  std::vector<Counter> counters() const override { return queries_.counters(); }
  void reset_counters() override { queries_.reset_counters(); }

 protected:
  QueryState& queries_;
  std::uint64_t units_;
};

/// Another thread's state, slowed the same way.
class SlowedState final : public SlowedQueries<QueryState> {
 public:
  SlowedState(std::unique_ptr<QueryState> inner, std::uint64_t units)
      : SlowedQueries<QueryState>(*inner, units), inner_(std::move(inner)) {}

 private:
  std::unique_ptr<QueryState> inner_;  // owns what the base forwards to
};

/// The method, with extra_work() before every query; everything else forwarded unchanged (batch
/// calls too, when the method answers in batches).
class SlowedMethod final : public SlowedQueries<Method>, public BatchAnswers {
 public:
  // The base takes *inner before inner_ takes the pointer: the Method it refers to never moves.
  SlowedMethod(std::unique_ptr<Method> inner, std::string knob, std::uint64_t units)
      : SlowedQueries<Method>(*inner, units), inner_(std::move(inner)), knob_(std::move(knob)) {}

  void build(const Mesh& mesh, const BuildContext& ctx) override {
    warn();
    inner_->build(mesh, ctx);
  }
  bool reads_structure() const override { return inner_->reads_structure(); }
  void open(const MeshSummary& mesh, const BuildContext& ctx) override {
    warn();
    inner_->open(mesh, ctx);
  }
  bool supports(QueryType q) const override { return inner_->supports(q); }
  void set_query_options(const Params& params) override { inner_->set_query_options(params); }
  bool answers_in_batches() const override { return batch_answers(*inner_) != nullptr; }
  void inside_batch(const std::vector<Vec3d>& points, std::vector<std::uint8_t>& inside) override {
    for (std::size_t i = 0; i < points.size(); ++i) extra_work(units_);
    batch_answers(*inner_)->inside_batch(points, inside);
  }
  void distance_batch(const std::vector<Vec3d>& points, std::vector<DistanceResult>& out) override {
    for (std::size_t i = 0; i < points.size(); ++i) extra_work(units_);
    batch_answers(*inner_)->distance_batch(points, out);
  }
  std::map<std::string, std::string> build_options_read() const override { return inner_->build_options_read(); }
  std::optional<nlohmann::json> build_threads_read() const override { return inner_->build_threads_read(); }
  std::unique_ptr<QueryState> new_query_state() const override {
    auto state = inner_->new_query_state();
    if (!state) return nullptr;
    return std::make_unique<SlowedState>(std::move(state), units_);
  }
  std::size_t structure_bytes() const override { return inner_->structure_bytes(); }
  nlohmann::json info() const override {
    nlohmann::json j = inner_->info();
    if (!j.is_object()) j = nlohmann::json::object();
    j["TEST_SLOWDOWN"] = {{"knob", knob_}, {"units_per_query", units_}};
    return j;
  }
  nlohmann::json machine_facts() const override { return inner_->machine_facts(); }

 private:
  void warn() const {
    std::cerr << "bvhbench: TEST KNOB BVHBENCH_TEST_SLOWDOWN=" << knob_ << " is set: every query of this "
              << "method runs " << units_ << " rounds of extra work. These timings are NOT the method's.\n";
  }
  std::unique_ptr<Method> inner_;
  std::string knob_;
};

}  // namespace

std::unique_ptr<Method> apply_test_slowdown(std::unique_ptr<Method> method, const std::string& name) {
  const char* env = std::getenv("BVHBENCH_TEST_SLOWDOWN");
  if (env == nullptr || *env == '\0') return method;
  const std::string knob(env);
  const auto colon = knob.rfind(':');
  const std::string target = colon == std::string::npos ? std::string() : knob.substr(0, colon);
  const std::string units_text = colon == std::string::npos ? std::string() : knob.substr(colon + 1);
  std::uint64_t units = 0;
  bool digits = !units_text.empty() && units_text.size() <= 10;
  for (char c : units_text) digits = digits && c >= '0' && c <= '9';
  if (digits) units = std::stoull(units_text);
  if (target.empty() || !digits || units < 1 || units > 1000000000ull)
    throw InputError("BVHBENCH_TEST_SLOWDOWN='" + knob +
                     "': expected METHOD:UNITS (a method name, and a whole number of rounds 1..1000000000)");
  if (target != name) return method;
  return std::make_unique<SlowedMethod>(std::move(method), knob, units);
}

}  // namespace bvhbench
