#include "agvslam/slam/slam_config.h"

#include "agvslam/core/param_table.h"

namespace agvslam::slam {
namespace {

using params::Range;

const params::Table<TrackingConfig>& tracking_params() {
  using T = TrackingConfig;
  static const params::Table<T> table =
      params::Table<T>(
          "tracking",
          {
              {"close_depth_baselines", &T::close_depth_baselines, Range::left_open(1, 1000), "baselines"},
              {"min_init_features", &T::min_init_features, Range::at_least(10)},
              {"min_init_stereo", &T::min_init_stereo, Range::at_least(10)},
              {"motion_model_radius_px", &T::motion_model_radius_px, Range::closed(1, 100), "px"},
              {"min_motion_model_matches", &T::min_motion_model_matches, Range::at_least(5)},
              {"min_frame_inliers", &T::min_frame_inliers, Range::at_least(3)},
              {"min_reference_matches", &T::min_reference_matches, Range::any()},
              {"reference_ratio", &T::reference_ratio, Range::left_open(0, 1)},
              {"bow_matching", &T::bow_matching},
              {"local_map_radius", &T::local_map_radius, Range::left_open(0, 20), "x the level's scale"},
              {"min_local_map_inliers", &T::min_local_map_inliers, Range::any()},
              {"max_local_keyframes", &T::max_local_keyframes, Range::at_least(2)},
              {"keyframe_max_frames", &T::keyframe_max_frames, Range::at_least(0), "frames", "0: the frame rate"},
              {"keyframe_min_frames", &T::keyframe_min_frames, Range::at_least(0), "frames"},
              {"keyframe_ref_ratio", &T::keyframe_ref_ratio, Range::left_open(0, 1)},
              {"keyframe_close_tracked", &T::keyframe_close_tracked, Range::at_least(0)},
              {"keyframe_close_untracked", &T::keyframe_close_untracked, Range::at_least(0)},
              {"keyframe_max_new_points", &T::keyframe_max_new_points, Range::at_least(0)},
              {"keyframe_revisit_distance_m", &T::keyframe_revisit_distance_m, Range::closed(0, 10), "m", "0: off"},
              {"keyframe_revisit_angle_deg", &T::keyframe_revisit_angle_deg, Range::left_open(0, 90), "deg"},
              {"keyframe_revisit_shared", &T::keyframe_revisit_shared, Range::left_open(0, 1), "", "of the inliers"},
              {"keyframe_revisit_min_age_s", &T::keyframe_revisit_min_age_s, Range::at_least(0), "s"},
              {"keyframe_stop_speed_mps", &T::keyframe_stop_speed_mps, Range::closed(0, 10), "m/s"},
              {"keyframe_stop_distance_m", &T::keyframe_stop_distance_m, Range::closed(0, 100), "m", "0: off"},
              {"reset_max_keyframes", &T::reset_max_keyframes, Range::at_least(0)},
              {"reset_after_lost_frames", &T::reset_after_lost_frames, Range::at_least(1), "frames"},
              {"keyframe_queue_wait_ms", &T::keyframe_queue_wait_ms, Range::closed(0, 5000), "ms", "0: no wait"},
              {"keyframe_queue_wait_weak_ms", &T::keyframe_queue_wait_weak_ms, Range::closed(0, 5000), "ms"},
              {"new_map_after_lost_s", &T::new_map_after_lost_s, Range::closed(0, 3600), "s", "0: never"},
          })
          .check(
              "min_init_stereo", [](const T& t) { return t.min_init_stereo <= t.min_init_features; },
              "at most min_init_features")
          .check(
              "min_reference_matches", [](const T& t) { return t.min_reference_matches >= t.min_frame_inliers; },
              "at least min_frame_inliers")
          .check(
              "min_local_map_inliers", [](const T& t) { return t.min_local_map_inliers >= t.min_frame_inliers; },
              "at least min_frame_inliers")
          .check(
              "keyframe_queue_wait_weak_ms",
              [](const T& t) { return t.keyframe_queue_wait_weak_ms >= t.keyframe_queue_wait_ms; },
              "at least keyframe_queue_wait_ms");
  return table;
}

const params::Table<LocalMappingConfig>& mapping_params() {
  using M = LocalMappingConfig;
  static const params::Table<M> table(
      "mapping",
      {
          {"queue_capacity", &M::queue_capacity, Range::closed(1, 100), "keyframes"},
          {"triangulation_neighbours", &M::triangulation_neighbours, Range::at_least(1), "keyframes"},
          {"triangulation_bow", &M::triangulation_bow},
          {"fusion_neighbours", &M::fusion_neighbours, Range::at_least(0), "keyframes"},
          {"fusion_second_order", &M::fusion_second_order, Range::at_least(0), "keyframes"},
          {"fusion_radius", &M::fusion_radius, Range::left_open(0, 20), "x the level's scale"},
          {"local_ba_iterations_first", &M::local_ba_iterations_first, Range::at_least(0)},
          {"local_ba_iterations_second", &M::local_ba_iterations_second, Range::at_least(0)},
          {"max_local_ba_keyframes", &M::max_local_ba_keyframes, Range::at_least(1)},
          {"map_point_min_found_ratio", &M::map_point_min_found_ratio, Range::closed(0, 1)},
          {"map_point_min_observations", &M::map_point_min_observations, Range::at_least(1), "keyframes"},
          {"keyframe_redundancy", &M::keyframe_redundancy, Range::left_open(0, 1), "", "of the keyframe's points"},
          {"keyframe_redundancy_observers", &M::keyframe_redundancy_observers, Range::at_least(1), "keyframes"},
          {"max_keyframes", &M::max_keyframes, Range::at_least(10) | Range::value(0), "", "0: no cap"},
      });
  return table;
}

const params::Table<OptimizerConfig>& optimizer_params() {
  using O = OptimizerConfig;
  static const params::Table<O> table =
      params::Table<O>("optimizer",
                       {
                           {"chi2_mono", &O::chi2_mono, Range::above(0), "", "chi-square with 2 DOF"},
                           {"chi2_stereo", &O::chi2_stereo, Range::above(0), "", "chi-square with 3 DOF"},
                           {"motion_rounds", &O::motion_rounds, Range::closed(1, 20)},
                           {"motion_iterations", &O::motion_iterations, Range::closed(1, 100), "per round"},
                           {"motion_robust_rounds", &O::motion_robust_rounds, Range::at_least(0)},
                           {"local_ba_dense_schur", &O::local_ba_dense_schur},
                       })
          .check(
              "motion_robust_rounds", [](const O& o) { return o.motion_robust_rounds <= o.motion_rounds; },
              "at most motion_rounds");
  return table;
}

const params::Table<RelocalisationConfig>& relocalisation_params() {
  using R = RelocalisationConfig;
  static const params::Table<R> table =
      params::Table<R>("relocalisation",
                       {
                           {"max_candidates", &R::max_candidates, Range::at_least(1), "keyframes"},
                           {"min_bow_matches", &R::min_bow_matches, Range::at_least(4), "", "PnP needs 4 points"},
                           {"bow_ratio", &R::bow_ratio, Range::left_open(0, 1)},
                           {"pnp_iterations", &R::pnp_iterations, Range::closed(1, 100000)},
                           {"pnp_reprojection_px", &R::pnp_reprojection_px, Range::left_open(0, 50), "px"},
                           {"min_pnp_inliers", &R::min_pnp_inliers, Range::at_least(4), "", "PnP needs 4 points"},
                           {"min_inliers", &R::min_inliers, Range::any()},
                           {"projection_radius_px", &R::projection_radius_px, Range::left_open(0, 100), "px"},
                       })
          .check(
              "min_inliers", [](const R& r) { return r.min_inliers >= r.min_pnp_inliers; }, "at least min_pnp_inliers");
  return table;
}

const params::Table<LoopClosingConfig>& loop_closing_params() {
  using L = LoopClosingConfig;
  static const params::Table<L> table =
      params::Table<L>(
          "loop_closing",
          {
              {"enabled", &L::enabled},
              {"queue_capacity", &L::queue_capacity, Range::closed(1, 1000), "keyframes"},
              {"min_keyframes_between_loops", &L::min_keyframes_between_loops, Range::at_least(0), "keyframes"},
              {"consistency", &L::consistency, Range::closed(0, 20), "groups"},
              {"covisible_consistency", &L::covisible_consistency, Range::closed(0, 5), "keyframes", "0: off"},
              {"confirmation_max_m", &L::confirmation_max_m, Range::above(0), "m"},
              {"confirmation_max_deg", &L::confirmation_max_deg, Range::above(0), "deg"},
              {"bow_ratio", &L::bow_ratio, Range::left_open(0, 1)},
              {"min_bow_matches", &L::min_bow_matches, Range::at_least(3), "", "the SE(3) RANSAC samples 3 points"},
              {"ransac_iterations", &L::ransac_iterations, Range::closed(1, 100000)},
              {"ransac_chi2", &L::ransac_chi2, Range::above(0), "", "chi-square with 2 DOF"},
              {"min_ransac_inliers", &L::min_ransac_inliers, Range::at_least(3), "",
               "the SE(3) RANSAC samples 3 points"},
              {"projection_radius_px", &L::projection_radius_px, Range::left_open(0, 100), "px"},
              {"min_refined_inliers", &L::min_refined_inliers, Range::at_least(3), "", "an SE(3) needs 3 points"},
              {"min_total_matches", &L::min_total_matches, Range::any()},
              {"max_correction_m", &L::max_correction_m, Range::at_least(0), "m", "0: no limit"},
              {"essential_min_weight", &L::essential_min_weight, Range::at_least(15), "shared map points",
               "ORB-SLAM2's covisibility edges start at 15"},
              {"pose_graph_iterations", &L::pose_graph_iterations, Range::closed(1, 1000)},
              {"global_ba", &L::global_ba},
              {"global_ba_iterations", &L::global_ba_iterations, Range::closed(1, 1000)},
          })
          .check(
              "min_total_matches", [](const L& l) { return l.min_total_matches >= l.min_refined_inliers; },
              "at least min_refined_inliers");
  return table;
}

const params::Table<RetirementConfig>& retirement_params() {
  using R = RetirementConfig;
  static const params::Table<R> table =
      params::Table<R>("retirement",
                       {
                           {"enabled", &R::enabled},
                           {"window_frames", &R::window_frames, Range::closed(1, 16), "frames"},
                           {"min_frames", &R::min_frames, Range::at_least(1), "frames"},
                           {"chi2_mono", &R::chi2_mono, Range::above(0), "", "chi-square with 2 DOF"},
                           {"chi2_stereo", &R::chi2_stereo, Range::above(0), "", "chi-square with 3 DOF"},
                           {"depth_chi2", &R::depth_chi2, Range::above(0), "", "chi-square with 1 DOF"},
                           {"probe_sigma_px", &R::probe_sigma_px, Range::above(0), "px"},
                           {"probe_half_size_px", &R::probe_half_size_px, Range::closed(1, 3),
                            "px"},  // the reference patch holds 7 x 7
                           {"probe_min_zncc", &R::probe_min_zncc, Range::left_open(0, 1)},
                           {"probe_min_contrast", &R::probe_min_contrast, Range::at_least(0), "grey levels"},
                       })
          .check(
              "min_frames", [](const R& r) { return r.min_frames <= r.window_frames; }, "at most window_frames");
  return table;
}

}  // namespace

void TrackingConfig::validate(const std::string& source) const { tracking_params().validate(source, *this); }
std::string TrackingConfig::describe() const { return tracking_params().describe(*this); }

void LocalMappingConfig::validate(const std::string& source) const { mapping_params().validate(source, *this); }
std::string LocalMappingConfig::describe() const { return mapping_params().describe(*this); }

void OptimizerConfig::validate(const std::string& source) const { optimizer_params().validate(source, *this); }
std::string OptimizerConfig::describe() const { return optimizer_params().describe(*this); }

void RelocalisationConfig::validate(const std::string& source) const {
  relocalisation_params().validate(source, *this);
}
std::string RelocalisationConfig::describe() const { return relocalisation_params().describe(*this); }

void LoopClosingConfig::validate(const std::string& source) const { loop_closing_params().validate(source, *this); }
std::string LoopClosingConfig::describe() const { return loop_closing_params().describe(*this); }

void RetirementConfig::validate(const std::string& source) const { retirement_params().validate(source, *this); }
std::string RetirementConfig::describe() const { return retirement_params().describe(*this); }

void SlamConfig::validate(const std::string& source) const {
  tracking.validate(source);
  mapping.validate(source);
  optimizer.validate(source);
  relocalisation.validate(source);
  loop_closing.validate(source);
  retirement.validate(source);
}

std::vector<std::string> SlamConfig::describe() const {
  return {tracking.describe(),       mapping.describe(),      optimizer.describe(),
          relocalisation.describe(), loop_closing.describe(), retirement.describe()};
}

SlamConfig load_slam_config(const std::string& path) {
  SlamConfig c;
  params::read_sections(params::File(path),
                        {tracking_params().reader(c.tracking), mapping_params().reader(c.mapping),
                         optimizer_params().reader(c.optimizer), relocalisation_params().reader(c.relocalisation),
                         loop_closing_params().reader(c.loop_closing), retirement_params().reader(c.retirement)});
  c.validate(path);
  return c;
}

}  // namespace agvslam::slam
