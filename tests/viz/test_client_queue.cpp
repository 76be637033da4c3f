// The bounded queue of one browser (viz/server/client_queue.hpp): whatever is offered, it holds at
// most its limits, drops the oldest of the same kind first, counts every drop, keeps the newest.
#include <gtest/gtest.h>

#include <string>

#include "viz/server/client_queue.hpp"

namespace stride::viz {
namespace test_client_queue {

FrameText frame(int i, std::size_t size) {
  std::string text = std::to_string(i);
  text.resize(size, ' ');
  return std::make_shared<const std::string>(std::move(text));
}

int number(const FrameText& text) {
  return std::stoi(*text);
}

// A client that never drains: 100000 states offered, the queue stays within its byte cap after
// every offer, every frame beyond what it holds is counted as dropped, and what it holds is the
// newest frames, in order.
TEST(ClientQueue, NeverDrainedStaysUnderItsCapAndKeepsTheNewest) {
  const QueueLimits limits{1000, 64 * 1024};  // the byte cap binds: 64 frames of 1 KiB
  ClientQueue queue(limits);
  constexpr int kOffered = 100000;
  constexpr std::size_t kSize = 1024;
  std::size_t max_bytes = 0;
  for (int i = 0; i < kOffered; ++i) {
    queue.offer(FrameKind::State, frame(i, kSize));
    max_bytes = std::max(max_bytes, queue.bytes());
    ASSERT_LE(queue.bytes(), limits.max_bytes) << "after offer " << i;
    ASSERT_LE(queue.frames(), limits.max_frames);
  }
  const std::size_t held = limits.max_bytes / kSize;
  EXPECT_EQ(queue.frames(), held);
  EXPECT_EQ(queue.bytes(), held * kSize);
  EXPECT_EQ(max_bytes, held * kSize);
  EXPECT_EQ(queue.offered(), static_cast<std::uint64_t>(kOffered));
  EXPECT_EQ(queue.dropped(), static_cast<std::uint64_t>(kOffered - held));
  EXPECT_EQ(queue.droppedBytes(), queue.dropped() * kSize);
  for (std::size_t k = 0; k < held; ++k)
    EXPECT_EQ(number(queue.pop()), kOffered - static_cast<int>(held) + static_cast<int>(k));
  EXPECT_EQ(queue.pop(), nullptr);
  EXPECT_EQ(queue.bytes(), 0u);
}

TEST(ClientQueue, TheFrameCountBindsToo) {
  ClientQueue queue({8, 1u << 30});
  for (int i = 0; i < 100000; ++i) queue.offer(FrameKind::Plan, frame(i, 10));
  EXPECT_EQ(queue.frames(), 8u);
  EXPECT_EQ(queue.dropped(), 100000u - 8u);
  EXPECT_EQ(number(queue.pop()), 100000 - 8);
}

// Streams of several kinds: a new state drops the oldest state; a new kind drops the oldest frame
// of the kind most queued; the model the page needs stays.
TEST(ClientQueue, DropsTheOldestOfTheSameKindAndKeepsTheModel) {
  ClientQueue queue({4, 1u << 20});
  queue.offer(FrameKind::Model, frame(-1, 100));
  queue.offer(FrameKind::Plan, frame(-2, 100));
  for (int i = 0; i < 1000; ++i) queue.offer(FrameKind::State, frame(i, 100));
  // [model, plan, 998, 999]: the states superseded each other.
  EXPECT_EQ(queue.dropped(), 998u);
  queue.offer(FrameKind::Status, frame(-3, 100));  // no status queued: the older of two states goes
  EXPECT_EQ(queue.frames(), 4u);
  EXPECT_EQ(queue.dropped(), 999u);
  EXPECT_EQ(number(queue.pop()), -1);  // the model
  EXPECT_EQ(number(queue.pop()), -2);  // the plan
  EXPECT_EQ(number(queue.pop()), 999);
  EXPECT_EQ(number(queue.pop()), -3);
  EXPECT_EQ(queue.pop(), nullptr);
}

// A frame larger than the whole cap cannot be queued: it is dropped (counted), nothing else is.
TEST(ClientQueue, AFrameOverTheByteCapIsDroppedAlone) {
  ClientQueue queue({16, 1000});
  queue.offer(FrameKind::Model, frame(1, 100));
  queue.offer(FrameKind::Plan, frame(2, 5000));
  EXPECT_EQ(queue.frames(), 1u);
  EXPECT_EQ(queue.dropped(), 1u);
  EXPECT_EQ(number(queue.pop()), 1);
}

TEST(ClientQueue, DrainedItPassesEveryFrameInOrder) {
  ClientQueue queue({4, 1u << 20});
  for (int i = 0; i < 1000; ++i) {
    queue.offer(i % 2 ? FrameKind::State : FrameKind::Plan, frame(i, 50));
    EXPECT_EQ(number(queue.pop()), i);
  }
  EXPECT_EQ(queue.dropped(), 0u);
}

}  // namespace test_client_queue
}  // namespace stride::viz
