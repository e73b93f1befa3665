// Entry point of the map server nodelet (gmm_localization/MapServerNodelet): builds one
// MapServer (include/gmm_localization/ros/map_server.h).
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "gmm_localization/ros/map_server.h"

namespace gmm_localization {
namespace node {

class MapServerNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      server_ = std::make_unique<MapServer>(getNodeHandle(), getPrivateNodeHandle(), getName());
    } catch (const std::exception& e) {
      // The nodelet loader reports exceptions at DEBUG level only: say it loudly first.
      NODELET_FATAL("map_server: %s", e.what());
      throw;
    }
  }

  std::unique_ptr<MapServer> server_;
};

}  // namespace node
}  // namespace gmm_localization

PLUGINLIB_EXPORT_CLASS(gmm_localization::node::MapServerNodelet, nodelet::Nodelet)
