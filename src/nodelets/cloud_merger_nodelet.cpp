// Entry point of the cloud merger nodelet (gmm_localization/CloudMergerNodelet): builds one
// CloudMerger (include/gmm_localization/ros/cloud_merger.h).
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "gmm_localization/ros/cloud_merger.h"

namespace gmm_localization {
namespace node {

class CloudMergerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      merger_ = std::make_unique<CloudMerger>(getNodeHandle(), getPrivateNodeHandle(), getName());
    } catch (const std::exception& e) {
      // The nodelet loader reports exceptions at DEBUG level only: say it loudly first.
      NODELET_FATAL("cloud_merger: %s", e.what());
      throw;
    }
  }

  std::unique_ptr<CloudMerger> merger_;
};

}  // namespace node
}  // namespace gmm_localization

PLUGINLIB_EXPORT_CLASS(gmm_localization::node::CloudMergerNodelet, nodelet::Nodelet)
