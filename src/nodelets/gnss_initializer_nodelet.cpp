// Entry point of the GNSS initializer nodelet (gmm_localization/GnssInitializerNodelet): builds
// one GnssInitializer (include/gmm_localization/ros/gnss_initializer.h).
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "gmm_localization/ros/gnss_initializer.h"

namespace gmm_localization {
namespace node {

class GnssInitializerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      initializer_ =
          std::make_unique<GnssInitializer>(getNodeHandle(), getPrivateNodeHandle(), getName());
    } catch (const std::exception& e) {
      // The nodelet loader reports exceptions at DEBUG level only: say it loudly first.
      NODELET_FATAL("gnss_initializer: %s", e.what());
      throw;
    }
  }

  std::unique_ptr<GnssInitializer> initializer_;
};

}  // namespace node
}  // namespace gmm_localization

PLUGINLIB_EXPORT_CLASS(gmm_localization::node::GnssInitializerNodelet, nodelet::Nodelet)
