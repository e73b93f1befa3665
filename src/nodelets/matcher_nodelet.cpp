// Entry point of the matcher nodelet (gmm_localization/MatcherNodelet): builds one Matcher
// (include/gmm_localization/ros/matcher.h).
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "gmm_localization/ros/matcher.h"

namespace gmm_localization {
namespace node {

class MatcherNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      matcher_ = std::make_unique<Matcher>(getNodeHandle(), getPrivateNodeHandle(), getName());
    } catch (const std::exception& e) {
      // The nodelet loader reports exceptions at DEBUG level only: say it loudly first.
      NODELET_FATAL("matcher: %s", e.what());
      throw;
    }
  }

  std::unique_ptr<Matcher> matcher_;
};

}  // namespace node
}  // namespace gmm_localization

PLUGINLIB_EXPORT_CLASS(gmm_localization::node::MatcherNodelet, nodelet::Nodelet)
