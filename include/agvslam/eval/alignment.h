#pragma once
// Least-squares similarity/rigid alignment of point sets (Umeyama 1991).

#include <Eigen/Core>
#include <string>

#include "agvslam/core/se3.h"

namespace agvslam::eval {

enum class AlignMode { kNone, kSE3, kSim3 };

// "none" | "se3" | "sim3"; throws InputError naming option_name otherwise.
AlignMode parse_align_mode(const std::string& value, const std::string& option_name = "--align");
std::string to_string(AlignMode mode);

// dst_i ~= scale * (T_dst_src.linear() * src_i) + T_dst_src.translation()
struct Alignment {
  SE3d T_dst_src = SE3d::Identity();
  double scale = 1.0;

  Eigen::Vector3d apply(const Eigen::Vector3d& p_src) const {
    return scale * (T_dst_src.linear() * p_src) + T_dst_src.translation();
  }
  // Maps a pose of the source frame into the destination frame (translation scaled, rotation composed).
  SE3d apply(const SE3d& T_src_x) const;
};

// Needs at least 3 non-collinear points for a unique rotation; with fewer, or degenerate input, the
// rotation falls back to what the SVD gives (still a proper rotation). src and dst are 3xN, N >= 1.
Alignment umeyama(const Eigen::Matrix3Xd& src, const Eigen::Matrix3Xd& dst, bool with_scale);

}  // namespace agvslam::eval
