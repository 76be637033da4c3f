#pragma once
// The loops that drive an MpcNode (stride-mpc's modes) and the summary it prints at the end.

#include <atomic>
#include <string>

#include "controller/mpc_node.hpp"
#include "controller/statistics.hpp"

namespace stride {

struct RunOptions {
  double duration = 0.0;  // s of wall time (0: until stopped)
  const std::atomic<bool>* stop = nullptr;
};

// Real time: a tick every 1/rate on CLOCK_MONOTONIC (absolute sleeps), the solve's deadline a
// fraction of the period; a tick that ends after the next one was due counts as a deadline miss.
void runRealTime(MpcNode& node, lcm::LCM& in, const RunOptions& options);
// Stamps: ticks when a state reaches the next tick time (lock-step with the mock robot, or a log
// replay); no deadline. Returns when the input ends (a log's end), the duration passes or stop.
void runOnStamps(MpcNode& node, lcm::LCM& in, const RunOptions& options);

// Tries CPU pinning and SCHED_FIFO; prints a clear warning for each that is not permitted.
void applyRealTimeSettings(int cpu, int fifo_priority);

// The node's tick latencies [ms] (the last ones it kept, MpcNode::latencies).
Percentiles summarizeLatencies(const MpcNode& node);

// A human summary on stdout and, when path is not empty, the same as JSON.
void writeSummary(const MpcNode& node, const std::string& path);

}  // namespace stride
