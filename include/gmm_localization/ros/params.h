#pragma once
// Typed parameter loading with validation, done once at start (DESIGN.md 3): a missing key
// takes the default; a present key of the wrong type or out of range throws ConfigError naming
// the key, the value and the allowed range. onInit() catches it, logs NODELET_FATAL, rethrows.

#include <sstream>
#include <stdexcept>
#include <string>

#include <ros/ros.h>

namespace gmm_localization {
namespace node {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

template <typename T>
T param(const ros::NodeHandle& nh, const std::string& key, const T& default_value) {
  if (!nh.hasParam(key)) return default_value;
  T value;
  if (!nh.getParam(key, value)) {
    throw ConfigError("parameter " + nh.resolveName(key) + " has the wrong type");
  }
  return value;
}

/// As param(), and requires lo <= value <= hi.
template <typename T>
T param(const ros::NodeHandle& nh, const std::string& key, const T& default_value, const T& lo,
        const T& hi) {
  const T value = param<T>(nh, key, default_value);
  if (!(value >= lo && value <= hi)) {
    std::ostringstream os;
    os << "parameter " << nh.resolveName(key) << " = " << value << " is outside [" << lo << ", "
       << hi << "]";
    throw ConfigError(os.str());
  }
  return value;
}

/// Throws ConfigError with `what` when `problem` is non-empty (for options' validate()).
inline void requireValid(const std::string& what, const std::string& problem) {
  if (!problem.empty()) throw ConfigError(what + ": " + problem);
}

}  // namespace node
}  // namespace gmm_localization
