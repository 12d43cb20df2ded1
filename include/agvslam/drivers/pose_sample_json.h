#pragma once
// A PoseSample's SI values as JSON: the one format of the daemon's pose log (log.pose_log) and of
// agvslam-pose-replay --json, which can_log_check and the tests read ("t", "R" row-major, "cov_pose" row-major 6x6,
// "v_base_mps", "w_base_radps", state and counters).

#include <nlohmann/json.hpp>

#include "agvslam/drivers/pose_sample.h"

namespace agvslam::drivers {

inline nlohmann::json pose_sample_to_json(const PoseSample& s) {
  const Eigen::Vector3d& t = s.T_map_base.translation();
  const Eigen::Matrix3d& R = s.T_map_base.linear();
  nlohmann::json r = nlohmann::json::array();
  for (int i = 0; i < 9; ++i) r.push_back(R(i / 3, i % 3));
  nlohmann::json cov = nlohmann::json::array();
  for (int i = 0; i < 36; ++i) cov.push_back(s.cov_pose(i / 6, i % 6));
  return {{"t_ns", s.t_ns},
          {"t", {t.x(), t.y(), t.z()}},
          {"R", r},
          {"cov_pose", cov},
          {"v_base_mps", {s.v_base_mps.x(), s.v_base_mps.y(), s.v_base_mps.z()}},
          {"w_base_radps", {s.w_base_radps.x(), s.w_base_radps.y(), s.w_base_radps.z()}},
          {"tracking_state", static_cast<int>(s.tracking_state)},
          {"map_id", s.map_id},
          {"frame_index", s.frame_index},
          {"frames_processed", s.frames_processed},
          {"frames_dropped", s.frames_dropped},
          {"fps", s.fps},
          {"dynamic_pixel_fraction", s.dynamic_pixel_fraction},
          {"latency_ns", s.latency_ns}};
}

}  // namespace agvslam::drivers
