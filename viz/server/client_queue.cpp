#include "viz/server/client_queue.hpp"

#include <algorithm>

namespace stride::viz {

namespace {
bool isStreamed(FrameKind kind) {
  return kind == FrameKind::State || kind == FrameKind::Plan || kind == FrameKind::Status ||
         kind == FrameKind::Terrain;
}
}  // namespace

const char* toString(FrameKind kind) {
  switch (kind) {
    case FrameKind::Info:
      return "info";
    case FrameKind::Model:
      return "model";
    case FrameKind::State:
      return "state";
    case FrameKind::Plan:
      return "plan";
    case FrameKind::Status:
      return "status";
    case FrameKind::Terrain:
      return "terrain";
  }
  return "?";
}

ClientQueue::ClientQueue(QueueLimits limits) : limits_(limits) {
  // A queue that cannot hold one frame would drop everything: at least one.
  limits_.max_frames = std::max<std::size_t>(limits_.max_frames, 1);
}

bool ClientQueue::overLimits() const {
  return queue_.size() > limits_.max_frames || bytes_ > limits_.max_bytes;
}

void ClientQueue::dropAt(std::deque<Entry>::iterator it) {
  const std::size_t size = it->text ? it->text->size() : 0;
  bytes_ -= size;
  dropped_bytes_ += size;
  queue_.erase(it);
  ++dropped_;
}

void ClientQueue::offer(FrameKind kind, FrameText text) {
  ++offered_;
  const std::size_t size = text ? text->size() : 0;
  if (size > limits_.max_bytes) {  // it could only be queued alone, and not even so
    ++dropped_;
    dropped_bytes_ += size;
    return;
  }
  bytes_ += size;
  queue_.push_back({kind, std::move(text)});
  while (overLimits()) {
    const auto newest = std::prev(queue_.end());
    auto victim =
        std::find_if(queue_.begin(), newest, [kind](const Entry& e) { return e.kind == kind; });
    // None of its kind: the oldest of the streamed kind with the most frames queued (the most
    // superseded). The model and info frames come once or once a second and the page cannot draw
    // without the model: they go last.
    if (victim == newest) {
      int count[kFrameKinds] = {};
      for (auto it = queue_.begin(); it != newest; ++it)
        if (isStreamed(it->kind)) ++count[static_cast<int>(it->kind)];
      const int most = static_cast<int>(std::max_element(count, count + kFrameKinds) - count);
      if (count[most] > 0)
        victim = std::find_if(queue_.begin(), newest,
                              [most](const Entry& e) { return static_cast<int>(e.kind) == most; });
    }
    if (victim == newest) victim = queue_.begin();
    dropAt(victim);
  }
}

FrameText ClientQueue::pop() {
  if (queue_.empty()) return nullptr;
  FrameText text = std::move(queue_.front().text);
  bytes_ -= text ? text->size() : 0;
  queue_.pop_front();
  return text;
}

}  // namespace stride::viz
