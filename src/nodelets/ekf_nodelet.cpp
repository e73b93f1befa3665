// Entry point of the EKF nodelet (gmm_localization/EkfNodelet): builds one EkfNode
// (include/gmm_localization/ros/ekf_node.h).
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "gmm_localization/ros/ekf_node.h"

namespace gmm_localization {
namespace node {

class EkfNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      ekf_ = std::make_unique<EkfNode>(getNodeHandle(), getPrivateNodeHandle(), getName());
    } catch (const std::exception& e) {
      // The nodelet loader reports exceptions at DEBUG level only: say it loudly first.
      NODELET_FATAL("ekf: %s", e.what());
      throw;
    }
  }

  std::unique_ptr<EkfNode> ekf_;
};

}  // namespace node
}  // namespace gmm_localization

PLUGINLIB_EXPORT_CLASS(gmm_localization::node::EkfNodelet, nodelet::Nodelet)
