#pragma once
// Where a node's encoded messages go: LCM in the programs, a recorder or a sink in tests (which
// must not depend on a transport to check what a node sends).

#include <lcm/lcm-cpp.hpp>
#include <string>

namespace stride {

class Publisher {
 public:
  virtual ~Publisher() = default;
  virtual void publish(const std::string& channel, const void* data, int size) = 0;
};

class LcmPublisher : public Publisher {
 public:
  explicit LcmPublisher(lcm::LCM& lcm) : lcm_(lcm) {}
  void publish(const std::string& channel, const void* data, int size) override {
    failures_ += lcm_.publish(channel, data, static_cast<unsigned>(size)) != 0;
  }
  long failures() const { return failures_; }

 private:
  lcm::LCM& lcm_;
  long failures_ = 0;
};

}  // namespace stride
