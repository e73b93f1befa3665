// Entry point of the global start nodelet (gmm_localization/GlobalStartNodelet): builds
// one GlobalStart (include/gmm_localization/ros/global_start.h).
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "gmm_localization/ros/global_start.h"

namespace gmm_localization {
namespace node {

class GlobalStartNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      start_ = std::make_unique<GlobalStart>(getNodeHandle(), getPrivateNodeHandle(), getName());
    } catch (const std::exception& e) {
      // The nodelet loader reports exceptions at DEBUG level only: say it loudly first.
      NODELET_FATAL("global_start: %s", e.what());
      throw;
    }
  }

  std::unique_ptr<GlobalStart> start_;
};

}  // namespace node
}  // namespace gmm_localization

PLUGINLIB_EXPORT_CLASS(gmm_localization::node::GlobalStartNodelet, nodelet::Nodelet)
