#pragma once
// The frames waiting to be written to one browser. A browser that reads slower than frames come
// (a background tab, a slow link, a client that never reads) must cost the server a bounded amount
// of memory and nothing else: the queue holds at most `max_frames` frames and `max_bytes` bytes,
// and an offer beyond either limit drops the oldest queued frame of the same kind (a newer state
// supersedes an older one), else the oldest state, plan, status or terrain of the kind most queued,
// else the oldest frame. Dropped frames are counted: the server reports them to the browser (info
// frames) and at exit.
//
// Not thread-safe: the server guards each client's queue with that client's mutex.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>

namespace stride::viz {

// What a frame is (viz/README.md, "Frames"): the queue drops by kind.
enum class FrameKind : std::uint8_t { Info, Model, State, Plan, Status, Terrain };
constexpr int kFrameKinds = 6;
const char* toString(FrameKind kind);

// A frame's text is shared by every client it goes to.
using FrameText = std::shared_ptr<const std::string>;

struct QueueLimits {
  std::size_t max_frames = 32;
  std::size_t max_bytes = 2u << 20;  // 2 MiB
};

class ClientQueue {
 public:
  explicit ClientQueue(QueueLimits limits = {});

  // Queues a frame, then drops frames while a limit is exceeded: the oldest of the same kind
  // first, else the oldest state, plan or status of the kind most queued, else the oldest. A frame
  // larger than max_bytes alone is dropped at once. Never blocks, never grows past the limits.
  void offer(FrameKind kind, FrameText text);
  // The oldest frame, removed from the queue; nullptr when empty.
  FrameText pop();

  std::size_t frames() const { return queue_.size(); }
  std::size_t bytes() const { return bytes_; }
  std::uint64_t offered() const { return offered_; }
  std::uint64_t dropped() const { return dropped_; }
  std::uint64_t droppedBytes() const { return dropped_bytes_; }
  const QueueLimits& limits() const { return limits_; }

 private:
  struct Entry {
    FrameKind kind;
    FrameText text;
  };
  bool overLimits() const;
  void dropAt(std::deque<Entry>::iterator it);

  QueueLimits limits_;
  std::deque<Entry> queue_;
  std::size_t bytes_ = 0;
  std::uint64_t offered_ = 0, dropped_ = 0, dropped_bytes_ = 0;
};

}  // namespace stride::viz
