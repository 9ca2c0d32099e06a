#pragma once
// The topic table: every topic's name, message type and QoS preset, in one place. Names are
// the same for every robot; robots are kept apart by partition (see participant.h).

#include <string_view>

#include "common/bus/qos.h"
#include "rslam/msg/all_messages.h"

namespace rslam::bus {

template <class T>
struct Topic {
  using Type = T;
  std::string_view name;
  QosPreset qos;
};

// A topic without its C++ type, for tools that handle every topic alike (the recorder).
struct TopicInfo {
  std::string_view name;
  std::string_view type_name;
  QosPreset qos;
};

namespace topics {
inline constexpr Topic<msg::Image> kCameraImage{"camera/image", QosPreset::kSensor};
inline constexpr Topic<msg::Velocity> kOdometryVelocity{"odometry/velocity", QosPreset::kStream};
inline constexpr Topic<msg::Velocity> kWheelOdometry{"robot/wheel_odometry", QosPreset::kStream};
inline constexpr Topic<msg::ViewTemplate> kTemplatesView{"templates/view", QosPreset::kStream};
inline constexpr Topic<msg::PoseCellAction> kPoseCellsAction{"pose_cells/action", QosPreset::kLog};
inline constexpr Topic<msg::ExperiencePose> kExperienceMapPose{"experience_map/pose", QosPreset::kStream};
inline constexpr Topic<msg::ExperienceMap> kExperienceMapMap{"experience_map/map", QosPreset::kState};
inline constexpr Topic<msg::ObstacleProfile> kOccupancyProfile{"occupancy/profile", QosPreset::kStream};
inline constexpr Topic<msg::OccupancyGrid> kOccupancyGrid{"occupancy/grid", QosPreset::kState};
inline constexpr Topic<msg::MotionCommand> kExplorerCommand{"explorer/command", QosPreset::kStream};
inline constexpr Topic<msg::ExplorerStatus> kExplorerStatus{"explorer/status", QosPreset::kState};
inline constexpr Topic<msg::MotionFeedback> kMotionFeedback{"robot/motion_feedback", QosPreset::kStream};
inline constexpr Topic<msg::GroundTruthPose> kGroundTruth{"sim/ground_truth", QosPreset::kStream};
// The simulator's camera, read by the camera service as its source (like a device).
inline constexpr Topic<msg::Image> kSimCamera{"sim/camera", QosPreset::kSensor};
inline constexpr Topic<msg::ServiceStatus> kStatus{"rslam/status", QosPreset::kState};

// Every topic above, for iteration.
template <class T>
constexpr TopicInfo Info(const Topic<T>& t) {
  return {t.name, MessageTraits<T>::kTypeName, t.qos};
}
inline constexpr TopicInfo kAll[] = {
    Info(kCameraImage),      Info(kOdometryVelocity), Info(kWheelOdometry),     Info(kTemplatesView),
    Info(kPoseCellsAction),  Info(kExperienceMapPose), Info(kExperienceMapMap), Info(kOccupancyProfile),
    Info(kOccupancyGrid),    Info(kExplorerCommand),  Info(kExplorerStatus),    Info(kMotionFeedback),
    Info(kGroundTruth),      Info(kSimCamera),        Info(kStatus),
};
}  // namespace topics

}  // namespace rslam::bus
