// The protocol and the session's flow control without sockets (STYLE 4).
#include <gtest/gtest.h>

#include <thread>

#include "core/generators.h"
#include "session/protocol.h"
#include "session/session.h"

using namespace peakcast;
using namespace peakcast::protocol;

namespace {

TEST(Protocol, ParsesEachMessageType) {
  auto h = std::get<Hello>(parse_client_message(
      R"({"type":"hello","token":"t","viewport":{"width":100,"height":50,"dpr":2},"state":{"camera":{"eye":[0,0,5],"center":[0,0,0]}}})"));
  EXPECT_EQ(h.viewport.pixel_width(), 200);
  EXPECT_EQ(h.token, "t");
  ASSERT_TRUE(h.state.camera);
  EXPECT_TRUE(std::holds_alternative<CameraMsg>(
      parse_client_message(R"({"type":"camera","camera":{"eye":[0,0,5],"center":[0,0,0]}})")));
  auto tf =
      std::get<TfMsg>(parse_client_message(R"({"type":"tf","version":7,"tf":{"points":[[0,0,0,0,0],[1,1,1,1,1]]}})"));
  EXPECT_EQ(tf.version, 7u);
  EXPECT_EQ(std::get<AckMsg>(parse_client_message(R"({"type":"ack","frame":3})")).frame, 3u);
  EXPECT_TRUE(std::holds_alternative<PingMsg>(parse_client_message(R"({"type":"ping"})")));
}

TEST(Protocol, RefusalsCarryACode) {
  auto code = [](const std::string& text) {
    try {
      parse_client_message(text);
    } catch (const ProtocolError& e) {
      return e.code;
    }
    return std::string("accepted");
  };
  EXPECT_EQ(code("{"), "bad_json");
  EXPECT_EQ(code(R"({"type":"dance"})"), "unknown_type");
  EXPECT_EQ(code(R"({"type":"camera","camera":{"eye":[0,0,0],"center":[0,0,0]}})"), "bad_message");
  EXPECT_EQ(code(R"({"type":"viewport","width":9000,"height":10})"), "bad_message");
  EXPECT_EQ(code(std::string(300 * 1024, ' ')), "too_large");
}

TEST(Protocol, FrameHeaderRoundTrips) {
  FrameHeader h;
  h.frame_id = 42;
  h.flags = FrameHeader::kFinal | FrameHeader::kPng;
  h.camera_version = 3;
  h.width = 640;
  h.height = 480;
  h.t_input_us = 1234567890123ull;
  auto bytes = encode_frame(h, {1, 2, 3});
  ASSERT_EQ(bytes.size(), 67u);
  EXPECT_EQ(bytes[0], 'P');
  FrameHeader back = decode_frame_header(bytes.data(), bytes.size());
  EXPECT_EQ(back.frame_id, 42u);
  EXPECT_EQ(back.flags, h.flags);
  EXPECT_EQ(back.t_input_us, h.t_input_us);
  EXPECT_THROW(decode_frame_header(bytes.data(), 10), ProtocolError);
}

std::shared_ptr<VolumeEntry> entry() {
  GeneratorSpec g;
  g.dims = {8, 8, 8};
  auto e = std::make_shared<VolumeEntry>();
  e->id.assign(1, 'v');  // (a plain "v" trips GCC 12's false -Wrestrict)
  e->volume = std::make_shared<Volume>(generate_volume(g));
  return e;
}

TEST(SessionFlow, AtMostTwoFramesInFlightNewestStateWins) {
  Session s("s1", {});
  Viewport vp{100, 80, 1.0};
  s.start(entry(), vp, {});
  const auto still = std::chrono::milliseconds(150);
  const auto rate = std::chrono::duration<double>(0.0);
  Clock::time_point wake;
  auto t = Clock::now();
  auto a = s.take_job(t, still, rate, wake);
  ASSERT_TRUE(a);
  EXPECT_FALSE(a->final);
  EXPECT_EQ(a->scene.scene.width, 50);  // interactive: half resolution
  Camera c = a->scene.camera;
  for (int i = 0; i < 50; ++i) {  // fast input coalesces
    c.eye.x += 1;
    s.set_camera(c);
  }
  auto b = s.take_job(Clock::now(), still, rate, wake);
  ASSERT_TRUE(b);
  EXPECT_EQ(b->camera_version, 51u);
  c.eye.x += 1;
  s.set_camera(c);
  EXPECT_FALSE(s.take_job(Clock::now(), still, rate, wake)) << "two un-acked frames: no third";
  EXPECT_EQ(wake, Clock::time_point::max());
  s.ack(a->frame_id);
  auto d = s.take_job(Clock::now() + std::chrono::seconds(1), still, rate, wake);
  ASSERT_TRUE(d);
  EXPECT_TRUE(d->final) << "input quiet for longer than the still delay";
  EXPECT_EQ(d->scene.scene.width, 100);
  EXPECT_EQ(d->camera_version, 52u);
  s.ack(b->frame_id);
  s.ack(d->frame_id);
  EXPECT_FALSE(s.take_job(Clock::now() + std::chrono::seconds(2), still, rate, wake)) << "nothing new after the final";
}

TEST(SessionFlow, FinalFollowsInteractiveAfterTheStillDelay) {
  Session s("s2", {});
  s.start(entry(), Viewport{64, 64, 1.0}, {});
  Clock::time_point wake;
  const auto t0 = Clock::now();
  auto a = s.take_job(t0, std::chrono::milliseconds(150), std::chrono::duration<double>(0), wake);
  ASSERT_TRUE(a && !a->final);
  s.ack(a->frame_id);
  EXPECT_FALSE(s.take_job(t0 + std::chrono::milliseconds(10), std::chrono::milliseconds(150),
                          std::chrono::duration<double>(0), wake));
  EXPECT_NE(wake, Clock::time_point::max()) << "the render thread must wake for the still";
  auto b = s.take_job(wake, std::chrono::milliseconds(150), std::chrono::duration<double>(0), wake);
  ASSERT_TRUE(b);
  EXPECT_TRUE(b->final);
}

// A 400x400 view whose camera moves: each call takes the next interactive frame and returns its
// width (the budget tests).
struct MovingView {
  Session s{"budget", {}};
  Camera c;
  Clock::time_point wake;
  const std::chrono::milliseconds still{150};
  const std::chrono::duration<double> rate{0.0};
  int first_width = -1;
  MovingView() {
    s.start(entry(), Viewport{400, 400, 1.0}, {});
    auto a = s.take_job(Clock::now(), still, rate, wake);
    EXPECT_TRUE(a && !a->final);
    if (!a) return;
    c = a->scene.camera;
    first_width = a->scene.scene.width;
    s.ack(a->frame_id);
  }
  int next_interactive() {
    c.eye.x += 1;
    s.set_camera(c);
    auto j = s.take_job(Clock::now(), still, rate, wake);
    EXPECT_TRUE(j && !j->final);
    if (j) s.ack(j->frame_id);
    return j ? j->scene.scene.width : -1;
  }
};

TEST(SessionFlow, InteractiveFramesShrinkToHoldTheirBudgetAndRecover) {
  MovingView v;
  Session& s = v.s;
  auto next_interactive = [&] { return v.next_interactive(); };
  EXPECT_EQ(v.first_width, 200) << "nothing measured yet: interactive_scale";
  s.interactive_rendered(200 * 200, 60.0);  // twice the 30 ms budget
  // 0.5 * sqrt(30 / 60) = 0.354, down to a 64th: 22/64 of 400 pixels.
  EXPECT_EQ(next_interactive(), 137);
  for (int k = 0; k < 20; ++k) s.interactive_rendered(200 * 200, 1000.0);
  EXPECT_EQ(next_interactive(), 100) << "never below half the interactive scale";
  for (int k = 0; k < 20; ++k) s.interactive_rendered(100 * 100, 1.0);
  EXPECT_EQ(next_interactive(), 200) << "fast frames: back to interactive_scale, never above";
  s.interactive_rendered(0, 5.0);  // ignored: no pixels, or no time
  s.interactive_rendered(100, std::nan(""));
  EXPECT_EQ(next_interactive(), 200);
  for (int k = 0; k < 20; ++k) s.interactive_rendered(200 * 200, 1000.0);
  protocol::QualityMsg q;
  q.interactive_ms = 0.0;  // a fixed scale
  s.set_quality(q);
  EXPECT_EQ(next_interactive(), 200);
  auto f = s.take_job(Clock::now() + std::chrono::seconds(1), v.still, v.rate, v.wake);
  ASSERT_TRUE(f && f->final);
  EXPECT_EQ(f->scene.scene.width, 400) << "final frames are never reduced";
}

// The budget's model keeps a fixed part apart from the part per pixel (a distributed frame's
// broadcast and compositing): frames of two sizes costing 24 ms plus 1e-4 ms a pixel leave a
// 200x200 frame within 30 ms, where a cost per pixel alone (1.06e-3 ms) would shrink it; a
// fixed part above the budget gives the smallest frame; frames of one size give a cost per
// pixel alone.
TEST(SessionFlow, InteractiveBudgetKeepsTheFixedPartApart) {
  MovingView v;
  Session& s = v.s;
  auto next_interactive = [&] { return v.next_interactive(); };
  for (int k = 0; k < 10; ++k) {
    const int64_t pixels = k % 2 ? 200 * 200 : 100 * 100;
    s.interactive_rendered(pixels, 24.0 + 1e-4 * double(pixels));
  }
  EXPECT_EQ(next_interactive(), 200);
  for (int k = 0; k < 10; ++k) {
    const int64_t pixels = k % 2 ? 200 * 200 : 100 * 100;
    s.interactive_rendered(pixels, 40.0 + 1e-4 * double(pixels));
  }
  EXPECT_EQ(next_interactive(), 100);
  for (int k = 0; k < 20; ++k) s.interactive_rendered(150 * 150, 40.0);  // one size: per pixel only
  // 30 ms of 40 ms at 150x150: sqrt(0.75) * 150 = 130 wide, down to a 64th of 400: 125.
  EXPECT_EQ(next_interactive(), 125);
}

TEST(Protocol, QualityInteractiveMsIsANumberOfMilliseconds) {
  auto q = std::get<QualityMsg>(parse_client_message(R"({"type":"quality","interactive_ms":45})"));
  EXPECT_EQ(q.interactive_ms, 45.0);
  for (const char* bad :
       {R"({"type":"quality","interactive_ms":-1})", R"({"type":"quality","interactive_ms":1001})",
        R"({"type":"quality","interactive_ms":"fast"})", R"({"type":"quality","interactive_ms":null})"}) {
    try {
      parse_client_message(bad);
      ADD_FAILURE() << bad << " was accepted";
    } catch (const ProtocolError& e) {
      EXPECT_NE(std::string(e.what()).find("quality.interactive_ms"), std::string::npos) << e.what();
    }
  }
}

}  // namespace
