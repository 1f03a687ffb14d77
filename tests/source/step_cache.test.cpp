// The render server's step sources and cache: reads of a real file, cache
// hits and misses, the background prefetch, and a step out of range.
#include <chrono>
#include <future>
#include <thread>

#include <catch2/catch.hpp>

#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/source/step_source.hpp>

using namespace crackvis;

TEST_CASE("the step cache reads once, hits after, and prefetches in the background", "[source]") {
  testing::TempDir dir;
  const auto sample = testing::writeSampleFile(dir.file("run.h5"), 3, 6);
  auto source = source::openLocalSource(dir.file("run.h5"));
  REQUIRE(source.isOk());
  CHECK((*source)->stepCount() == 6);
  CHECK((*source)->lattice().bondCount() == sample.lattice.bondCount());
  source::StepCache cache(std::move(source).value(), 2);

  auto first = cache.get(2);
  REQUIRE(first.isOk());
  CHECK(first->step->index == 2);
  CHECK(first->step->positions.size() == sample.lattice.particleCount());
  CHECK(first->step->bondState == sample.steps[2].bondState);
  auto again = cache.get(2);
  REQUIRE(again.isOk());
  CHECK(again->loadMs == 0.0);
  CHECK(again->step.get() == first->step.get());  // the same data, not a copy
  CHECK(cache.stats().hits == 1);
  CHECK(cache.stats().misses == 1);

  cache.prefetch(3);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (cache.stats().prefetched < 1 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  REQUIRE(cache.stats().prefetched == 1);
  auto prefetched = cache.get(3);
  REQUIRE(prefetched.isOk());
  CHECK(prefetched->loadMs == 0.0);
  CHECK(prefetched->step->positions == sample.steps[3].positions);

  // A step asked for just before: its prefetch is waited for, not read twice.
  cache.prefetch(1);
  auto asked = cache.get(1);
  REQUIRE(asked.isOk());
  CHECK(asked->step->positions == sample.steps[1].positions);
  CHECK(cache.stats().misses == 1);
  CHECK(cache.stats().prefetched == 2);
  CHECK(asked->loadMs >= 0.0);

  // Capacity 2: steps 3 and 1 are held; reading 4 and 5 evicts them.
  REQUIRE(cache.get(4).isOk());
  REQUIRE(cache.get(5).isOk());
  auto evicted = cache.get(2);
  REQUIRE(evicted.isOk());
  CHECK(cache.stats().misses == 4);

  auto outside = cache.get(6);
  REQUIRE_FALSE(outside.isOk());
  CHECK(outside.status().code() == StatusCode::kOutOfRange);
  CHECK(outside.status().message().find("step 6 out of range (the file has steps 0..5)") !=
        std::string::npos);
  cache.prefetch(99);  // ignored
}

namespace {

// A source whose read of one step blocks until released: the prefetch
// thread can be held in a read while the cache answers other calls.
class HeldSource final : public source::StepSource {
 public:
  explicit HeldSource(int held) : m_held(held) {}
  const std::string& file() const override { return m_file; }
  const dem::Lattice& lattice() const override { return m_lattice; }
  int stepCount() const override { return 8; }
  Status setExtraArrays(const source::ExtraArrays&) override { return Status::ok(); }
  const std::vector<std::int32_t>& breakSteps() const override { return m_breakSteps; }
  Result<source::SourceStep> read(int step) override {
    if (step == m_held) {
      m_entered.set_value();
      m_release.get_future().wait();
    }
    source::SourceStep out;
    out.index = step;
    return out;
  }
  std::future<void> entered() { return m_entered.get_future(); }
  void release() { m_release.set_value(); }

 private:
  int m_held;
  std::string m_file = "held.h5";
  dem::Lattice m_lattice;
  std::vector<std::int32_t> m_breakSteps;
  std::promise<void> m_entered;
  std::promise<void> m_release;
};

}  // namespace

TEST_CASE("a cached step is answered at once while the prefetch thread reads another", "[source]") {
  auto held = std::make_unique<HeldSource>(6);
  HeldSource& source = *held;
  auto entered = source.entered();
  source::StepCache cache(std::move(held), 4);
  REQUIRE(cache.get(4).isOk());
  cache.prefetch(6);
  REQUIRE(entered.wait_for(std::chrono::seconds(10)) == std::future_status::ready);
  // Asked for again while step 6's read holds the prefetch thread: still a
  // hit, not a wait for that read.
  cache.prefetch(4);
  auto again = std::async(std::launch::async, [&] { return cache.get(4); });
  const bool answered = again.wait_for(std::chrono::seconds(5)) == std::future_status::ready;
  source.release();
  REQUIRE(answered);
  auto hit = again.get();
  REQUIRE(hit.isOk());
  CHECK(hit->step->index == 4);
  CHECK(hit->loadMs == 0.0);
  CHECK(cache.stats().misses == 1);
  // Step 6 itself, once its read ends: the prefetched one.
  auto six = cache.get(6);
  REQUIRE(six.isOk());
  CHECK(six->step->index == 6);
  CHECK(cache.stats().misses == 1);
}

TEST_CASE("a step source brings velocities, bond forces and break steps only when asked",
          "[source]") {
  testing::TempDir dir;
  const auto sample = testing::writeSampleFile(dir.file("run.h5"), 3, 4);
  auto source = source::openLocalSource(dir.file("run.h5"));
  REQUIRE(source.isOk());
  auto plain = (*source)->read(2);
  REQUIRE(plain.isOk());
  CHECK(plain->velocities.empty());
  CHECK(plain->bondForce.empty());
  CHECK((*source)->breakSteps().empty());

  source::ExtraArrays extras;
  extras.velocities = true;
  extras.bondForce = true;
  extras.breakStep = true;
  REQUIRE((*source)->setExtraArrays(extras).isOk());
  auto full = (*source)->read(2);
  REQUIRE(full.isOk());
  CHECK(full->velocities == sample.steps[2].velocities);
  CHECK(full->bondForce == sample.steps[2].bondForce);
  CHECK((*source)->breakSteps().size() == sample.lattice.bondCount());

  // A file without the optional arrays: asked for, they stay empty.
  testing::writeSample(dir.file("bare.h5"), testing::makeSample(3, 2, false));
  auto bare = source::openLocalSource(dir.file("bare.h5"));
  REQUIRE(bare.isOk());
  REQUIRE((*bare)->setExtraArrays(extras).isOk());
  auto step = (*bare)->read(1);
  REQUIRE(step.isOk());
  CHECK(step->velocities.empty());
  CHECK(step->bondForce.empty());
}
