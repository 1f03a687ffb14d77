// The render server's step sources and cache: reads of a real file, cache
// hits and misses, the background prefetch, and a step out of range.
#include <chrono>
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
