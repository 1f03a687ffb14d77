// A render session's thread on its own (EGL, no gRPC): what no input may do
// to it. A step source or an opener that throws stands for any library that
// throws on data it should have refused; only that read or event fails.
#include <algorithm>
#include <atomic>
#include <chrono>
#include <mutex>
#include <stdexcept>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>

#include "support/forwarding_source.hpp"
#include "support/sample_files.hpp"
#include "support/temp_dir.hpp"
#include <crackvis/service/render_turns.hpp>
#include <crackvis/service/renderer_shelf.hpp>
#include <crackvis/service/session.hpp>

namespace crackvis {
namespace {

using service::Session;
using service::SessionEvent;
using service::SessionNotice;

// A local file's source whose read of one step throws, as std::vector does
// on a size it cannot hold.
class ThrowingSource : public testing::ForwardingSource {
 public:
  ThrowingSource(std::unique_ptr<source::StepSource> inner, int poisoned)
      : ForwardingSource(std::move(inner)), m_poisoned(poisoned) {}
  Result<source::SourceStep> read(int step) override {
    if (step == m_poisoned) {
      throw std::length_error("cannot create std::vector larger than max_size()");
    }
    return ForwardingSource::read(step);
  }

 private:
  int m_poisoned;
};

struct Fixture {
  testing::TempDir dir;
  Fixture() { testing::writeSampleFile(dir.file("run.h5"), 3, 3); }

  Session::SourceOpener opener(int poisoned) const {
    return
        [this, poisoned](const std::string& file) -> Result<std::unique_ptr<source::StepSource>> {
          auto inner = source::openLocalSource(dir.file(file));
          if (!inner) {
            return inner.status();
          }
          return std::unique_ptr<source::StepSource>(
              new ThrowingSource(std::move(inner).value(), poisoned));
        };
  }
};

pipeline::PipelineDescription smallView(std::int64_t step) {
  pipeline::PipelineDescription d;
  d.file = "run.h5";
  d.step = step;
  d.view.width = 64;
  d.view.height = 48;
  return d;
}

// The next notice for `eventId` (frames in between are skipped).
SessionNotice noticeFor(Session& session, std::uint64_t attachment, std::uint64_t eventId) {
  service::RenderedFrame frame;
  SessionNotice notice;
  const auto until = service::Clock::now() + std::chrono::seconds(30);
  while (service::Clock::now() < until) {
    const auto next = session.next(attachment, std::chrono::milliseconds(100), frame, notice);
    REQUIRE(next != Session::Next::kClosed);
    if (next == Session::Next::kNotice && notice.eventId == eventId) {
      return notice;
    }
  }
  FAIL("no notice for event " << eventId);
  return notice;
}

}  // namespace

TEST_CASE("a step source that throws fails only that read", "[session][render]") {
  const Fixture fixture;
  auto opened = Session::open("s1", smallView(0), fixture.opener(2), {});
  REQUIRE(opened);
  Session& session = **opened;
  const std::uint64_t attachment = session.attach();

  // Step 1 prefetches step 2 on the cache's thread: that read throws too.
  session.post({5, service::Clock::now(), service::SetStepEvent{1}});
  REQUIRE(noticeFor(session, attachment, 5).error);
  session.post({6, service::Clock::now(), service::SetStepEvent{2}});
  const SessionNotice failed = noticeFor(session, attachment, 6);
  CHECK(failed.error.code() == StatusCode::kInternal);
  CHECK_THAT(failed.error.message(), Catch::Contains("run.h5: reading step 2 failed"));
  CHECK_THAT(failed.error.message(), Catch::Contains("max_size"));
  CHECK_FALSE(session.closed());

  // The session goes on showing step 1.
  int step = -1;
  auto image = session.snapshot(0, 0, &step);
  REQUIRE(image);
  CHECK(step == 1);
  CHECK(image->width == 64);
  session.post({7, service::Clock::now(), service::SetStepEvent{0}});
  const SessionNotice moved = noticeFor(session, attachment, 7);
  CHECK(moved.error);
  REQUIRE(moved.state);
  CHECK(moved.state->step == 0);
}

TEST_CASE("an exception on a session's thread fails only that event", "[session][render]") {
  const Fixture fixture;
  // Opening any file but run.h5 throws (the opener runs on the session's
  // thread, outside the source's guard).
  auto opener = [inner = fixture.opener(-1)](const std::string& file) {
    if (file != "run.h5") {
      throw std::runtime_error("opener exploded on " + file);
    }
    return inner(file);
  };
  auto opened = Session::open("s2", smallView(1), opener, {});
  REQUIRE(opened);
  Session& session = **opened;
  const std::uint64_t attachment = session.attach();

  auto elsewhere = smallView(0);
  elsewhere.file = "other.h5";
  session.post(
      {5, service::Clock::now(), service::ReplacePipelineEvent{pipeline::toXml(elsewhere)}});
  const SessionNotice failed = noticeFor(session, attachment, 5);
  CHECK(failed.error.code() == StatusCode::kInternal);
  CHECK_THAT(failed.error.message(),
             Catch::Contains("session s2: replace_pipeline failed on an internal error: opener "
                             "exploded on other.h5"));
  CHECK_FALSE(session.closed());

  // The session goes on with its description and step.
  session.post({6, service::Clock::now(), service::StillEvent{}});
  int step = -1;
  REQUIRE(session.snapshot(0, 0, &step));
  CHECK(step == 1);
  session.post({7, service::Clock::now(), service::SetStepEvent{2}});
  const SessionNotice moved = noticeFor(session, attachment, 7);
  CHECK(moved.error);
  REQUIRE(moved.state);
  CHECK(moved.state->step == 2);
  CHECK_THAT(moved.state->pipelineXml, Catch::Contains("run.h5"));

  // Opening a session whose opener throws fails that session only.
  auto failing = Session::open("s3", elsewhere, opener, {});
  REQUIRE_FALSE(failing);
  CHECK(failing.status().code() == StatusCode::kInternal);
  CHECK_THAT(failing.status().message(), Catch::Contains("session s3: open failed"));
}

TEST_CASE("a session's queues stay bounded while its stream does not read", "[session][render]") {
  const Fixture fixture;
  auto opened = Session::open("s4", smallView(0), fixture.opener(-1), {});
  REQUIRE(opened);
  Session& session = **opened;
  const std::uint64_t attachment = session.attach();  // a stream that never reads

  // 400k events as fast as they come: camera moves of alternating kinds
  // (nothing to add up), step changes (each answered by a state) and bad
  // sizes (each answered by an error).
  constexpr std::uint64_t kEvents = 400'000;
  std::size_t mostEvents = 0;
  std::size_t mostNotices = 0;
  for (std::uint64_t id = 1; id <= kEvents; ++id) {
    SessionEvent event{id, service::Clock::now(), service::StillEvent{}};
    switch (id % 4) {
      case 0:
        event.what = service::CameraEvent{render::CameraMove::kRotate, 0.001, 0.0};
        break;
      case 1:
        event.what = service::CameraEvent{render::CameraMove::kPan, 0.001, 0.0};
        break;
      case 2:
        event.what = service::SetStepEvent{static_cast<int>(id / 4 % 3)};
        break;
      default:
        event.what = service::ResizeEvent{3, 3};
        break;
    }
    session.post(std::move(event));
    if (id % 1000 == 0) {
      const auto stats = session.queueStats();
      mostEvents = std::max(mostEvents, stats.events);
      mostNotices = std::max(mostNotices, stats.notices);
    }
  }
  const auto stats = session.queueStats();
  INFO("most events queued " << mostEvents << ", most notices " << mostNotices << ", refused "
                             << stats.refused << ", errors dropped " << stats.errorsDropped);
  const service::SessionLimits limits;
  CHECK(mostEvents <= limits.maxQueuedEvents);
  CHECK(mostNotices <= limits.maxQueuedErrors + 1);  // the errors and the newest state
  CHECK(stats.errorsDropped > 0);

  // The session still answers: once the stream has read what is queued, the
  // next event.
  CHECK_FALSE(session.closed());
  service::RenderedFrame frame;
  SessionNotice notice;
  while (session.next(attachment, std::chrono::milliseconds(500), frame, notice) !=
         Session::Next::kTimeout) {
  }
  session.post({kEvents + 1, service::Clock::now(), service::SetStepEvent{2}});
  const SessionNotice moved = noticeFor(session, attachment, kEvents + 1);
  CHECK(moved.error);
  REQUIRE(moved.state);
  CHECK(moved.state->step == 2);
}

TEST_CASE("camera moves queued back to back add up into one", "[session][render]") {
  const Fixture fixture;
  service::SessionLimits limits;
  limits.maxQueuedEvents = 4;
  auto opened = Session::open("s5", smallView(0), fixture.opener(-1), limits);
  REQUIRE(opened);
  Session& session = **opened;
  // Events arrive faster than the session's thread takes them: those that
  // meet a queued move of their kind join it.
  for (std::uint64_t id = 1; id <= 10'000; ++id) {
    session.post(
        {id, service::Clock::now(), service::CameraEvent{render::CameraMove::kZoom, 0.0, 0.0}});
  }
  const auto stats = session.queueStats();
  CHECK(stats.coalesced > 0);
  CHECK(stats.refused == 0);  // moves of one kind never fill the queue
  CHECK(stats.events <= 1);
}

TEST_CASE("a drag whose moves come in bunches is not broken up by full-resolution frames",
          "[session][render]") {
  const Fixture fixture;
  service::SessionLimits limits;
  limits.refineAfterMs = 50.0;
  limits.maxReduction = 4;
  // A budget no frame meets: every move is drawn reduced, so the only
  // full-resolution frames are the refinements after a pause.
  limits.interactiveFrameMs = 1.0;
  pipeline::PipelineDescription view = smallView(0);
  view.view.width = 320;
  view.view.height = 240;
  auto opened = Session::open("s6", view, fixture.opener(-1), limits);
  REQUIRE(opened);
  Session& session = **opened;
  const std::uint64_t attachment = session.attach();
  int full = 0;
  int reduced = 0;
  // Takes every frame published until `until`, counting how each was drawn.
  auto drain = [&](service::Clock::time_point until) {
    service::RenderedFrame frame;
    SessionNotice notice;
    while (service::Clock::now() < until) {
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(until - service::Clock::now());
      const auto next =
          session.next(attachment, std::max(left, std::chrono::milliseconds(1)), frame, notice);
      if (next == Session::Next::kFrame) {
        (frame.fullResolution ? full : reduced)++;
      }
    }
  };
  drain(service::Clock::now() + std::chrono::milliseconds(500));  // the first frame
  full = 0;
  // A drag of 16 bunches: three moves 10 ms apart, then 120 ms without any,
  // as a browser busy painting delivers them. Each gap is longer than
  // refine_after_ms, so a fixed wait would refine in every one of them.
  std::uint64_t id = 0;
  for (int bunch = 0; bunch < 16; ++bunch) {
    for (int move = 0; move < 3; ++move) {
      session.post({++id, service::Clock::now(),
                    service::CameraEvent{render::CameraMove::kRotate, 0.01, 0.0}});
      drain(service::Clock::now() + std::chrono::milliseconds(10));
    }
    drain(service::Clock::now() + std::chrono::milliseconds(120));
  }
  INFO("full-resolution frames during the drag: " << full << ", reduced: " << reduced);
  CHECK(reduced > 0);
  CHECK(full <= 4);  // the wait grows past the gaps after a refinement or two
  // At rest, the full-resolution frame still follows.
  full = 0;
  drain(service::Clock::now() + std::chrono::milliseconds(1500));
  CHECK(full >= 1);
  session.detach(attachment);
}

// A 320x240 session whose moves are drawn reduced (at most 1/4; with a
// budget of 1 ms every one), refined `refineAfterMs` after the last, its
// renders taking `turns`.
auto openDragged(const Fixture& fixture, const std::string& id, double refineAfterMs,
                 std::shared_ptr<service::RenderTurns> turns, double budgetMs = 1.0) {
  service::SessionLimits limits;
  limits.refineAfterMs = refineAfterMs;
  limits.interactiveFrameMs = budgetMs;
  limits.maxReduction = 4;
  pipeline::PipelineDescription view = smallView(0);
  view.view.width = 320;
  view.view.height = 240;
  return Session::open(id, view, fixture.opener(-1), limits, std::move(turns));
}

TEST_CASE("render turns: at most so many at once, in the order asked", "[session][turns]") {
  SECTION("never more at once than allowed, and as many when asked") {
    for (int atOnce : {1, 2}) {
      service::RenderTurns turns(atOnce);
      CHECK(turns.atOnce() == atOnce);
      std::atomic<int> rendering{0};
      std::atomic<int> most{0};
      std::vector<std::thread> sessions;
      for (int k = 0; k < 6; ++k) {
        sessions.emplace_back([&] {
          for (int frame = 0; frame < 5; ++frame) {
            const auto turn = turns.take();
            const int now = ++rendering;
            int seen = most.load();
            while (now > seen && !most.compare_exchange_weak(seen, now)) {
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
            --rendering;
          }
        });
      }
      for (std::thread& session : sessions) {
        session.join();
      }
      CHECK(most.load() == atOnce);
    }
  }
  SECTION("first come, first served") {
    service::RenderTurns turns(1);
    std::vector<int> order;
    std::mutex orderMutex;
    std::vector<std::thread> waiting;
    {
      const auto held = turns.take();
      for (int k = 0; k < 3; ++k) {
        waiting.emplace_back([&, k] {
          const auto turn = turns.take();
          std::lock_guard lock(orderMutex);
          order.push_back(k);
        });
        // Each one in line before the next asks.
        std::this_thread::sleep_for(std::chrono::milliseconds(100));
      }
    }
    for (std::thread& thread : waiting) {
      thread.join();
    }
    CHECK(order == std::vector<int>{0, 1, 2});
  }
  SECTION("0 means the hardware threads") {
    CHECK(service::RenderTurns(0).atOnce() ==
          std::max(1, static_cast<int>(std::thread::hardware_concurrency())));
  }
  SECTION("a turn is crowded when another frame renders or waits, even with places free") {
    service::RenderTurns turns(2);
    CHECK_FALSE(turns.take().crowded());
    const auto other = turns.take();
    CHECK(turns.take().crowded());  // a place was free: no wait, yet crowded
  }
}

TEST_CASE("a drag beside another session's renders is drawn coarse, and alone in full detail",
          "[session][render][turns]") {
  // issue 34 point 3: llvmpipe rasterises all sessions' frames in turn, so
  // a crowded server's drag frames draw coarse stand-ins.
  const Fixture fixture;
  auto turns = std::make_shared<service::RenderTurns>(2);
  // A budget of 1 s: the factor soon falls to 1, where a coarse frame is
  // still no full-resolution one, and is refined.
  const double budgetMs = GENERATE(1.0, 1000.0);
  INFO("budget " << budgetMs << " ms");
  auto opened = openDragged(fixture, "s8", 150.0, turns, budgetMs);
  REQUIRE(opened);
  Session& session = **opened;
  const std::uint64_t attachment = session.attach();
  std::uint64_t id = 0;
  // Drags `moves` rotations 20 ms apart, reading the frames meanwhile (the
  // stream keeps only the latest); returns the drag's frames, until the one
  // that reflects its last move.
  auto drag = [&](int moves) {
    std::vector<service::RenderedFrame> frames;
    service::RenderedFrame frame;
    SessionNotice notice;
    auto readUntil = [&](service::Clock::time_point until, bool lastMove) {
      while (service::Clock::now() < until && !(lastMove && frame.lastEventId >= id)) {
        if (session.next(attachment, std::chrono::milliseconds(5), frame, notice) ==
            Session::Next::kFrame) {
          frames.push_back(frame);
        }
      }
    };
    for (int k = 0; k < moves; ++k) {
      session.post({++id, service::Clock::now(),
                    service::CameraEvent{render::CameraMove::kRotate, 0.01, 0.0}});
      readUntil(service::Clock::now() + std::chrono::milliseconds(20), false);
    }
    readUntil(service::Clock::now() + std::chrono::seconds(30), true);
    REQUIRE(frame.lastEventId == id);
    return frames;
  };
  auto coarseFrames = [](const std::vector<service::RenderedFrame>& frames) {
    return std::count_if(frames.begin(), frames.end(),
                         [](const service::RenderedFrame& f) { return f.coarse; });
  };
  // Drags in bunches of 5 moves until `done` holds for the last bunch's
  // frames, at most `most` bunches (a slow machine draws fewer frames per
  // bunch); returns every frame.
  auto dragUntil = [&](auto done, int most) {
    std::vector<service::RenderedFrame> all;
    for (int bunch = 0; bunch < most; ++bunch) {
      const auto frames = drag(5);
      all.insert(all.end(), frames.begin(), frames.end());
      if (done(frames)) {
        break;
      }
    }
    return all;
  };
  const auto alone = drag(15);
  INFO("frames alone: " << alone.size());
  CHECK(alone.size() >= 3);
  CHECK(coarseFrames(alone) == 0);
  std::vector<service::RenderedFrame> crowded;
  {
    const auto other = turns->take();  // another session renders all along
    crowded = dragUntil([](const auto& frames) { return frames.back().coarse; }, 20);
    // At rest, still crowded, the refinement follows: full resolution, in
    // full detail.
    service::RenderedFrame frame;
    SessionNotice notice;
    const auto until = service::Clock::now() + std::chrono::seconds(5);
    while (!frame.fullResolution && service::Clock::now() < until) {
      if (session.next(attachment, std::chrono::milliseconds(100), frame, notice) ==
          Session::Next::kFrame) {
        crowded.push_back(frame);
      }
    }
    CHECK(frame.fullResolution);
    CHECK_FALSE(frame.coarse);
  }
  INFO("frames beside another's: " << crowded.size());
  CHECK(coarseFrames(crowded) >= 1);
  // Alone again: back to full detail within a few frames (the crowded
  // share decays by 0.7 a frame, from coarse to full below 0.2).
  const auto after = dragUntil([](const auto& frames) { return !frames.back().coarse; }, 20);
  INFO("frames alone again: " << after.size());
  CHECK_FALSE(after.back().coarse);
  // A full-resolution frame (the refinement at rest) is never coarse.
  using Frames = std::vector<service::RenderedFrame>;
  for (const Frames* frames : std::initializer_list<const Frames*>{&alone, &crowded, &after}) {
    for (const auto& frame : *frames) {
      CHECK((frame.fullResolution ? !frame.coarse : true));
    }
  }
  session.detach(attachment);
}

TEST_CASE("a drag that waited for its render turn goes on with reduced frames",
          "[session][render][turns]") {
  // issue 34 point 3: a session that waited long for its turn found the
  // refinement planned after its previous reduced frame due, and drew a
  // full-resolution frame in the middle of the drag.
  const Fixture fixture;
  auto turns = std::make_shared<service::RenderTurns>(1);
  auto opened = openDragged(fixture, "s7", 50.0, turns);
  REQUIRE(opened);
  Session& session = **opened;
  const std::uint64_t attachment = session.attach();
  // The frames that reflect event `id` or later, until one does.
  auto frameFor = [&](std::uint64_t id) {
    service::RenderedFrame frame;
    SessionNotice notice;
    const auto until = service::Clock::now() + std::chrono::seconds(30);
    while (service::Clock::now() < until) {
      if (session.next(attachment, std::chrono::milliseconds(100), frame, notice) ==
              Session::Next::kFrame &&
          frame.lastEventId >= id) {
        return frame;
      }
    }
    FAIL("no frame for event " << id);
    return frame;
  };
  auto rotate = [&](std::uint64_t id) {
    session.post(
        {id, service::Clock::now(), service::CameraEvent{render::CameraMove::kRotate, 0.01, 0.0}});
  };
  frameFor(0);
  rotate(1);
  CHECK_FALSE(frameFor(1).fullResolution);
  std::uint64_t id = 1;
  {
    // Another session renders for 300 ms while this one's drag goes on.
    const auto other = turns->take();
    for (int k = 0; k < 10; ++k) {
      rotate(++id);
      std::this_thread::sleep_for(std::chrono::milliseconds(30));
    }
  }
  // Every frame of the drag's moves until the last move's: reduced (the
  // moves queued behind the wait are applied before the next frame, and
  // supersede the refinement planned after the frame that waited). A
  // refinement of move 1 may come first, rightly: where this test runs
  // slowly (under ASan), move 2 can follow move 1's frame by more than the
  // 50 ms after which a resting view is refined. So may the last move's
  // frame be full, rightly too: the drag has ended, and where the frame
  // that waited takes long (25-40 ms measured after the wait on one
  // machine), the last move is older than 50 ms when its frame starts.
  std::vector<std::uint64_t> fullFor;  // the last event of each full-resolution frame
  service::RenderedFrame frame;
  SessionNotice notice;
  const auto until = service::Clock::now() + std::chrono::seconds(30);
  while (frame.lastEventId < id && service::Clock::now() < until) {
    if (session.next(attachment, std::chrono::milliseconds(100), frame, notice) ==
            Session::Next::kFrame &&
        frame.fullResolution) {
      fullFor.push_back(frame.lastEventId);
    }
  }
  REQUIRE(frame.lastEventId == id);
  INFO("full-resolution frames for events " << Catch::Detail::stringify(fullFor));
  CHECK(std::count_if(fullFor.begin(), fullFor.end(),
                      [&](std::uint64_t e) { return e > 1 && e < id; }) == 0);
  session.detach(attachment);
}

TEST_CASE(
    "a session's renderer serves the next session of its size, which sees nothing of the "
    "first",
    "[session][render]") {
  const Fixture fixture;
  auto shelf = std::make_shared<service::RendererShelf>();
  auto own = Session::open("own", smallView(0), fixture.opener(-1), {});
  REQUIRE(own);
  const auto expected = (*own)->snapshot(0, 0);
  REQUIRE(expected);
  own->reset();
  {
    // A first user sees another step, the bonds, another colour-by, and
    // turns the camera.
    pipeline::PipelineDescription other = smallView(2);
    other.bonds.show = pipeline::BondSelection::kAll;
    other.particles.colourBy = pipeline::ParticleColourBy::kRadius;
    auto first = Session::open("first", other, fixture.opener(-1), {}, nullptr, shelf);
    REQUIRE(first);
    (*first)->post({1, service::Clock::now(),
                    service::CameraEvent{render::CameraMove::kRotate, 0.2, 0.1, true}});
    const auto seen = (*first)->snapshot(0, 0);
    REQUIRE(seen);
    CHECK(seen->rgb != expected->rgb);
    CHECK(shelf->size() == 0);
  }
  // Its renderer waits, its scene dropped; the next session of its size
  // takes it and draws what a renderer of its own draws.
  auto drawsOnTheKeptRenderer = [&](const std::string& id) {
    REQUIRE(shelf->size() == 1);
    auto session = Session::open(id, smallView(0), fixture.opener(-1), {}, nullptr, shelf);
    REQUIRE(session);
    CHECK(shelf->size() == 0);
    const auto got = (*session)->snapshot(0, 0);
    REQUIRE(got);
    CHECK(got->rgb == expected->rgb);
  };
  drawsOnTheKeptRenderer("second");
  REQUIRE(shelf->size() == 1);

  // A session of another size makes its own and leaves the waiting one,
  // which its own then replaces (the newest is kept).
  pipeline::PipelineDescription larger = smallView(0);
  larger.view.width = 80;
  larger.view.height = 60;
  auto third = Session::open("third", larger, fixture.opener(-1), {}, nullptr, shelf);
  REQUIRE(third);
  CHECK(shelf->size() == 1);
  third->reset();
  CHECK(shelf->size() == 1);
  auto fourth = Session::open("fourth", larger, fixture.opener(-1), {}, nullptr, shelf);
  REQUIRE(fourth);
  CHECK(shelf->size() == 0);  // the one kept was the 80x60 one
  fourth->reset();
  CHECK(shelf->size() == 1);

  // A session whose file does not open shelves the renderer it made.
  pipeline::PipelineDescription missing = smallView(0);
  missing.file = "missing.h5";
  auto failed = Session::open("failed", missing, fixture.opener(-1), {}, nullptr, shelf);
  CHECK_FALSE(failed);
  CHECK(shelf->size() == 1);
  drawsOnTheKeptRenderer("again");
}

TEST_CASE("a new session waits for the renderer of its size that a closing session clears",
          "[session][render]") {
  using std::chrono::milliseconds;
  using Timer = std::chrono::steady_clock;
  auto elapsed = [](Timer::time_point since) {
    return std::chrono::duration_cast<milliseconds>(Timer::now() - since).count();
  };
  service::RendererShelf shelf;
  auto made = render::SceneRenderer::create(64, 48);
  REQUIRE(made);
  (*made)->releaseContext();
  std::unique_ptr<render::SceneRenderer> renderer = std::move(made).value();
  render::SceneRenderer* const returning = renderer.get();

  SECTION("it arrives: taken as soon as it is put") {
    shelf.expect(64, 48);
    std::atomic<bool> taken{false};
    const auto start = Timer::now();
    std::thread closing([&] {
      std::this_thread::sleep_for(milliseconds(80));
      shelf.put(std::move(renderer));
      // Settled only once the take has returned: the put alone ends its wait.
      while (!taken) {
        std::this_thread::sleep_for(milliseconds(1));
      }
      shelf.arrived(64, 48);
    });
    auto got = shelf.take(64, 48, milliseconds(5000));
    const auto waited = elapsed(start);
    taken = true;
    closing.join();
    CHECK(got.get() == returning);
    CHECK(waited >= 70);
    CHECK(waited < 4000);
    CHECK(shelf.expected(64, 48) == 0);
  }
  SECTION("it does not come: no wait beyond the news") {
    shelf.expect(64, 48);
    std::thread closing([&] {
      std::this_thread::sleep_for(milliseconds(80));
      shelf.arrived(64, 48);  // not sound: dropped, not shelved
    });
    const auto start = Timer::now();
    CHECK(shelf.take(64, 48, milliseconds(5000)) == nullptr);
    CHECK(elapsed(start) < 2000);
    closing.join();
  }
  SECTION("another size is not waited for, and the wait is bounded") {
    shelf.expect(64, 48);
    auto start = Timer::now();
    CHECK(shelf.take(80, 60, milliseconds(5000)) == nullptr);
    CHECK(elapsed(start) < 1000);
    start = Timer::now();
    CHECK(shelf.take(64, 48, milliseconds(100)) == nullptr);
    CHECK(elapsed(start) >= 90);
    shelf.arrived(64, 48);
  }
}

TEST_CASE("a full shelf keeps the renderer a take was woken for, and drops the one put",
          "[session][render]") {
  using std::chrono::milliseconds;
  service::RendererShelf shelf(1);
  auto makeReleased = [](int w, int h) {
    auto made = render::SceneRenderer::create(w, h);
    REQUIRE(made);
    (*made)->releaseContext();
    return std::move(made).value();
  };
  for (int round = 0; round < 5; ++round) {
    std::unique_ptr<render::SceneRenderer> awaited = makeReleased(64, 48);
    std::unique_ptr<render::SceneRenderer> other = makeReleased(80, 60);
    render::SceneRenderer* const expected = awaited.get();
    shelf.expect(64, 48);
    std::unique_ptr<render::SceneRenderer> got;
    std::thread taking([&] { got = shelf.take(64, 48, milliseconds(10000)); });
    const auto start = std::chrono::steady_clock::now();
    while (shelf.waiting(64, 48) == 0 &&
           std::chrono::steady_clock::now() - start < std::chrono::seconds(10)) {
      std::this_thread::sleep_for(milliseconds(1));
    }
    CHECK(shelf.waiting(64, 48) == 1);  // CHECK: the thread is joined below either way
    // Put, and at once another of another size: the second put finds the
    // shelf full of the renderer the take was woken for, unless the take
    // has had the lock already. Either way the take gets it.
    shelf.put(std::move(awaited));
    shelf.put(std::move(other));
    shelf.arrived(64, 48);
    taking.join();
    CHECK(got.get() == expected);
    CHECK(shelf.size() <= 1);
    CHECK(shelf.waiting(64, 48) == 0);
    (void)shelf.take(80, 60);  // empty for the next round
  }
}

TEST_CASE("a closing session announces its renderer to the shelf until it is there",
          "[session][render]") {
  const Fixture fixture;
  auto shelf = std::make_shared<service::RendererShelf>();
  auto opened = Session::open("closing", smallView(0), fixture.opener(-1), {}, nullptr, shelf);
  REQUIRE(opened);
  std::shared_ptr<Session> session = std::move(opened).value();
  REQUIRE((*session).snapshot(0, 0));
  CHECK(shelf->expected(64, 48) == 0);
  // A stream may still hold the session when CloseSession answers: the
  // worker clears the renderer after that.
  session->close();
  // Announced, unless the worker has shelved it already.
  const int announced = shelf->expected(64, 48);
  CHECK((announced == 1 || shelf->size() == 1));
  auto next = shelf->take(64, 48, std::chrono::milliseconds(5000));
  CHECK(next != nullptr);
  // Put, then settled: once the worker has ended, nothing is expected.
  session.reset();
  CHECK(shelf->size() == 0);
  CHECK(shelf->expected(64, 48) == 0);
  // A second close announces nothing more.
  auto again = Session::open("again", smallView(0), fixture.opener(-1), {}, nullptr, shelf);
  REQUIRE(again);
  (*again)->close();
  (*again)->close();
  again->reset();
  CHECK(shelf->expected(64, 48) == 0);
  CHECK(shelf->size() == 1);
  // A session whose file does not open leaves nothing expected.
  pipeline::PipelineDescription missing = smallView(0);
  missing.file = "missing.h5";
  CHECK_FALSE(Session::open("failed", missing, fixture.opener(-1), {}, nullptr, shelf));
  CHECK(shelf->expected(64, 48) == 0);
}

TEST_CASE("an ended session asks the server's trimmer, and trims nothing itself",
          "[session][render]") {
  const Fixture fixture;
  std::atomic<int> trimmed{0};
  auto trimmer = std::make_shared<service::HeapTrimmer>(
      service::HeapTrimmer::Timing{std::chrono::milliseconds(60000),
                                   std::chrono::milliseconds(60000)},
      [&] { ++trimmed; });
  for (const char* id : {"first", "second"}) {
    auto opened =
        Session::open(id, smallView(0), fixture.opener(-1), {}, nullptr, nullptr, trimmer);
    REQUIRE(opened);
    REQUIRE((*opened)->snapshot(0, 0));
    opened->reset();  // closed, its thread joined: the trim was asked for
  }
  // Both ends asked, a minute before any trim is due: none has run.
  CHECK(trimmer->trims() == 0);
  CHECK(trimmed == 0);
  // The trim still due runs as the trimmer goes (the server stopping): once
  // for both ends.
  trimmer.reset();
  CHECK(trimmed == 1);
}

}  // namespace crackvis
