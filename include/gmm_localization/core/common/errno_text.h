#pragma once
// The text of an errno value, for the messages of failed file operations.

#include <cstring>
#include <string>

namespace gmm_localization {

inline std::string errnoText(int e) { return std::string(std::strerror(e)); }

}  // namespace gmm_localization
