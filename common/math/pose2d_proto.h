#pragma once
// rslam::Pose2D to and from its saved form, rslam.proto.Pose2D (common/math/pose2d.proto).

#include "common/math/pose2d.h"
#include "common/math/pose2d.pb.h"

namespace rslam {

inline void SavePose(const Pose2D& p, proto::Pose2D* out) {
  out->set_x(p.x);
  out->set_y(p.y);
  out->set_theta(p.theta);
}

inline Pose2D LoadPose(const proto::Pose2D& p) { return {p.x(), p.y(), p.theta()}; }

}  // namespace rslam
