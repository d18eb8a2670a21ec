// The render thread's scheduling policy without GL (issue: scripted stills starved viewers): a
// bounded still queue, stills in bands alternating with viewers' frames, cancellation and shutdown.
#include <gtest/gtest.h>

#include "core/generators.h"
#include "session/scheduler.h"

using namespace peakcast;

namespace {

std::shared_ptr<VolumeEntry> entry() {
  GeneratorSpec g;
  g.dims = {16, 16, 16};
  auto e = std::make_shared<VolumeEntry>();
  e->id.assign(1, 'v');
  e->volume = std::make_shared<Volume>(generate_volume(g));
  return e;
}

StillJob still(const std::shared_ptr<VolumeEntry>& e, int w, int h, std::vector<std::string>* answers = nullptr) {
  Scene s;
  s.volume = "v";
  s.width = w;
  s.height = h;
  StillJob j;
  j.volume = e;
  j.scene = resolve_scene(s, *e->volume);
  j.done = [answers](StillResult r) {
    if (answers) answers->push_back(r.error_code.empty() ? "ok" : r.error_code);
  };
  return j;
}

// A viewer that always has new input and acks at once: it wants a frame every time it is asked.
struct BusyViewer {
  std::shared_ptr<Session> session = std::make_shared<Session>("busy", std::weak_ptr<FrameSink>{});
  explicit BusyViewer(const std::shared_ptr<VolumeEntry>& e) { session->start(e, protocol::Viewport{32, 32, 1.0}, {}); }
  void input() {
    Camera c;
    c.eye = {0, 0, 100};
    c.center = {0, 0, 0};
    session->set_camera(c);
  }
};

SchedulerOptions options(size_t max_queued, double band_samples) {
  SchedulerOptions o;
  o.max_queued_stills = max_queued;
  o.band_samples = band_samples;
  o.max_fps = 0;  // no frame-rate wait in these tests
  return o;
}

TEST(Scheduler, EstimatesSamplesFromTheBoxDiagonal) {
  auto e = entry();
  StillJob j = still(e, 10, 20);
  const double diag = std::sqrt(3.0) * 15.0;  // 16 voxels per side, spacing 1, step 1
  EXPECT_DOUBLE_EQ(estimated_samples_per_ray(j.scene), std::floor(diag) + 1);
  EXPECT_DOUBLE_EQ(estimated_still_samples(j.scene), 200 * (std::floor(diag) + 1));
  j.scene.step = 0.1;
  EXPECT_GT(estimated_samples_per_ray(j.scene), 250);
}

TEST(Scheduler, TheStillQueueIsBounded) {
  auto e = entry();
  Scheduler s(options(3, 1e9));
  EXPECT_TRUE(s.submit_still(still(e, 8, 8)));
  EXPECT_TRUE(s.submit_still(still(e, 8, 8)));
  EXPECT_TRUE(s.submit_still(still(e, 8, 8)));
  EXPECT_FALSE(s.submit_still(still(e, 8, 8))) << "a fourth still beyond max_queued_stills = 3";
  EXPECT_EQ(s.stills_pending(), 3u);
}

// A viewer's refinement (its view at rest at the finest level) and scripts' stills are counted
// apart: scripts filling max_queued_stills leave room for the refinement, and the refinement
// takes none of the scripts' places. Refinements: one live per viewer; a cancelled one (the view
// moved, or the viewer left) frees its place at once.
TEST(Scheduler, ViewersRefinementsAndScriptsStillsAreCountedApart) {
  auto e = entry();
  Scheduler s(options(2, 1e9));
  auto refinement = [&](const std::string& viewer) {
    StillJob j = still(e, 8, 8);
    j.refinement_of = viewer;
    return j;
  };
  StillJob first = refinement("a");
  auto first_cancelled = first.cancelled;
  EXPECT_TRUE(s.submit_still(std::move(first)));
  EXPECT_TRUE(s.submit_still(still(e, 8, 8)));
  EXPECT_TRUE(s.submit_still(still(e, 8, 8))) << "the refinement takes no script's place";
  EXPECT_FALSE(s.submit_still(still(e, 8, 8))) << "a third script still beyond max_queued_stills = 2";
  EXPECT_FALSE(s.submit_still(refinement("a"))) << "a second live refinement for one viewer";
  EXPECT_TRUE(s.submit_still(refinement("b"))) << "another viewer's refinement is not held back by the first's";
  first_cancelled->store(true);  // the view moved
  EXPECT_TRUE(s.submit_still(refinement("a"))) << "scripts' stills do not keep a view coarse";
  EXPECT_EQ(s.stills_pending(), 5u);
}

TEST(Scheduler, StillsComeInBandsThatAlternateWithViewersFrames) {
  auto e = entry();
  // 100 x 40 pixels x 26 samples per ray; 26,000 samples per band -> 10 rows per band, 4 bands.
  Scheduler s(options(4, 26000));
  BusyViewer v(e);
  s.add_session(v.session);
  std::vector<std::string> answers;
  ASSERT_TRUE(s.submit_still(still(e, 100, 40, &answers)));
  ASSERT_TRUE(s.submit_still(still(e, 100, 40, &answers)));
  std::string order;
  int bands = 0, rows = 0;
  for (int k = 0; k < 20 && bands < 8; ++k) {
    auto w = s.next();
    ASSERT_TRUE(w);
    if (w->frame) {
      order += 'F';
      v.session->ack(w->frame->frame_id);
      v.input();
    } else {
      ASSERT_TRUE(w->still);
      order += 'B';
      EXPECT_EQ(w->y0, w->still->next_row);
      EXPECT_EQ(w->rows, 10);
      w->still->next_row += w->rows;
      w->still->bands++;
      rows += w->rows;
      bands++;
      s.band_done(w->still);
    }
  }
  // A viewer's frame never waits for more than one band, and stills still make progress.
  EXPECT_EQ(order.substr(0, 16), "FBFBFBFBFBFBFBFB");
  EXPECT_EQ(rows, 80);
  EXPECT_EQ(s.stills_pending(), 0u);
}

TEST(Scheduler, WithoutViewersStillsRunBackToBack) {
  auto e = entry();
  Scheduler s(options(4, 1e12));
  ASSERT_TRUE(s.submit_still(still(e, 30, 30)));
  auto w = s.next();
  ASSERT_TRUE(w && w->still);
  EXPECT_EQ(w->rows, 30) << "a cheap still is one band";
}

TEST(Scheduler, CancelledStillsAreAnsweredNotRendered) {
  auto e = entry();
  Scheduler s(options(4, 1e12));
  StillJob a = still(e, 8, 8), b = still(e, 8, 8);
  auto flag = a.cancelled;
  ASSERT_TRUE(s.submit_still(std::move(a)));
  ASSERT_TRUE(s.submit_still(std::move(b)));
  flag->store(true);  // the client of the first still went away
  auto w = s.next();
  ASSERT_TRUE(w);
  ASSERT_EQ(w->cancelled.size(), 1u);
  ASSERT_TRUE(w->still);
  EXPECT_FALSE(w->still->job.cancelled->load()) << "the second still is the one rendered";
  EXPECT_EQ(s.stills_pending(), 1u);
}

TEST(Scheduler, ShutDownHandsBackQueuedStillsAndStopsHandingOutWork) {
  auto e = entry();
  Scheduler s(options(4, 1e12));
  ASSERT_TRUE(s.submit_still(still(e, 8, 8)));
  ASSERT_TRUE(s.submit_still(still(e, 8, 8)));
  auto w = s.next();  // the first is being rendered now
  ASSERT_TRUE(w && w->still);
  auto back = s.shut_down();
  EXPECT_EQ(back.size(), 1u) << "the queued one; the rendering one is answered by the render thread";
  EXPECT_TRUE(w->still->job.cancelled->load());
  EXPECT_FALSE(s.next());
  EXPECT_FALSE(s.submit_still(still(e, 8, 8)));
}

TEST(Scheduler, ShutDownWakesAWaitingRenderThread) {
  Scheduler s(options(4, 1e12));
  std::thread t([&] { EXPECT_FALSE(s.next()); });
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  s.shut_down();
  t.join();
}

}  // namespace
