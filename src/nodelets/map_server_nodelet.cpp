// MapServer nodelet: gets the shared map of its manager and publishes it (MapPublisher).
#include <memory>
#include <stdexcept>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "occupancy_fusion/ros/map_publisher.h"
#include "occupancy_fusion/ros/ros_parameter_source.h"
#include "occupancy_fusion/ros/shared_map_access.h"

namespace occupancy_fusion {

class MapServer : public nodelet::Nodelet {
 private:
  void onInit() override {
    const RosParameterSource parameters(getPrivateNodeHandle());
    try {
      std::shared_ptr<SharedMap> map = acquireSharedMap(parameters, getName());
      publisher_ =
          std::make_unique<MapPublisher>(getNodeHandle(), getPrivateNodeHandle(), getName(),
                                         std::move(map), readMapPublisherConfig(parameters));
    } catch (const std::invalid_argument& error) {
      NODELET_FATAL("invalid parameter: %s", error.what());
      throw;
    }
  }

  std::unique_ptr<MapPublisher> publisher_;
};

}  // namespace occupancy_fusion

PLUGINLIB_EXPORT_CLASS(occupancy_fusion::MapServer, nodelet::Nodelet)
