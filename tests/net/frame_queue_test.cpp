// A viewer's send queue (net/frame_queue.h): the newest frame replaces one waiting, an older one
// arriving late is dropped, video frames are never replaced or dropped, and the frame being
// written and text messages are left alone.
#include "net/frame_queue.h"

#include <gtest/gtest.h>

#include <deque>

using namespace peakcast;

namespace {

struct Entry {
  bool binary = true;
  bool video = false;
  uint32_t frame_id = 0;
};

Entry frame(uint32_t id, bool video = false) { return {true, video, id}; }
Entry text() { return {false, false, 0}; }

}  // namespace

TEST(FrameQueue, TheNewestFrameReplacesTheOneWaiting) {
  const std::deque<Entry> q{text(), frame(4), text()};
  const FramePlacement p = place_frame(q, 0, 5, false);
  ASSERT_TRUE(p.replace);
  EXPECT_EQ(*p.replace, 1u);
  EXPECT_FALSE(p.drop);
}

TEST(FrameQueue, AnOlderFrameArrivingLateIsDroppedNotTheNewerOne) {
  // A PNG final (3) rendered before an interactive JPEG (4) whose encode finished first.
  const std::deque<Entry> q{frame(2), frame(4), text()};
  const FramePlacement p = place_frame(q, 1, 3, false);
  EXPECT_TRUE(p.drop);
  EXPECT_FALSE(p.replace);
}

TEST(FrameQueue, TheFrameBeingWrittenIsNeverReplaced) {
  const std::deque<Entry> q{frame(4), text()};
  const FramePlacement written = place_frame(q, 1, 5, false);
  EXPECT_FALSE(written.replace);
  EXPECT_FALSE(written.drop);
  // Older than the one being written: still sent (the client draws over it), but not its stats.
  const FramePlacement late = place_frame(q, 1, 3, false);
  EXPECT_FALSE(late.replace);
  EXPECT_FALSE(late.drop);
  EXPECT_TRUE(stats_are_stale(3, 4));
  EXPECT_FALSE(stats_are_stale(4, 4));
}

TEST(FrameQueue, VideoFramesAreNeverReplacedNorDropped) {
  const std::deque<Entry> waiting_video{frame(4, true)};
  EXPECT_FALSE(place_frame(waiting_video, 0, 5, false).replace);
  EXPECT_FALSE(place_frame(waiting_video, 0, 5, true).replace);
  // A video frame older than a waiting final: queued behind it (the next delta refers to it).
  const std::deque<Entry> waiting_final{frame(6)};
  const FramePlacement p = place_frame(waiting_final, 0, 5, true);
  EXPECT_FALSE(p.drop);
  EXPECT_FALSE(p.replace);
  // A newer video frame replaces a waiting JPEG frame, as any newer frame does.
  ASSERT_TRUE(place_frame(waiting_final, 0, 7, true).replace);
}

TEST(FrameQueue, AnEmptyQueueOrTextsOnlyTakeTheFrame) {
  const std::deque<Entry> empty;
  const FramePlacement a = place_frame(empty, 0, 1, false);
  EXPECT_FALSE(a.replace || a.drop);
  const std::deque<Entry> texts{text(), text()};
  const FramePlacement b = place_frame(texts, 0, 1, false);
  EXPECT_FALSE(b.replace || b.drop);
}
