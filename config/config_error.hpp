#pragma once
// The one error type of the configuration files (robots, controller, plans): its message names the
// file and the key, so a user can fix the file without reading the code.

#include <stdexcept>

namespace stride {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace stride
