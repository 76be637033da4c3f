#pragma once
// The terminal in raw mode for as long as this object lives: keys arrive one byte at a time,
// unechoed, and Ctrl-C arrives as the byte 0x03 instead of a signal (so quitting runs the same
// path as the x key). Output processing stays on, so "\n" still starts a new line.
//
// The destructor restores the saved settings, so every exit that unwinds the stack (a return, an
// exception caught in main, the loop ending on SIGINT/SIGTERM) leaves the terminal as it was.

#include <termios.h>

namespace stride::teleop {

class RawTerminal {
 public:
  explicit RawTerminal(int fd);  // throws std::runtime_error when fd is not a terminal
  ~RawTerminal();
  RawTerminal(const RawTerminal&) = delete;
  RawTerminal& operator=(const RawTerminal&) = delete;

  void restore();  // idempotent

 private:
  int fd_;
  termios saved_{};
  bool active_ = false;
};

}  // namespace stride::teleop
