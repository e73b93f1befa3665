// Entry point of the INS adapter nodelet (gmm_localization/InsAdapterNodelet): builds one
// InsAdapter (include/gmm_localization/ros/ins_adapter.h).
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "gmm_localization/ros/ins_adapter.h"

namespace gmm_localization {
namespace node {

class InsAdapterNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    try {
      adapter_ = std::make_unique<InsAdapter>(getNodeHandle(), getPrivateNodeHandle(), getName());
    } catch (const std::exception& e) {
      // The nodelet loader reports exceptions at DEBUG level only: say it loudly first.
      NODELET_FATAL("ins_adapter: %s", e.what());
      throw;
    }
  }

  std::unique_ptr<InsAdapter> adapter_;
};

}  // namespace node
}  // namespace gmm_localization

PLUGINLIB_EXPORT_CLASS(gmm_localization::node::InsAdapterNodelet, nodelet::Nodelet)
