#include "agvslam/slam/slam_config.h"

#include <cstdio>

#include "agvslam/core/error.h"
#include "agvslam/stereo/params_reader.h"

namespace agvslam::slam {

namespace {

struct Checker {
  const std::string& source;
  const char* section;
  void operator()(bool ok, const char* field, const char* expected) const {
    if (!ok) throw InputError(source, std::string(section) + "." + field, expected);
  }
};

}  // namespace

void TrackingConfig::validate(const std::string& source) const {
  const Checker require{source, "tracking"};
  require(close_depth_baselines > 1 && close_depth_baselines <= 1000, "close_depth_baselines",
          "expected a number in (1, 1000] (baselines)");
  require(min_init_features >= 10, "min_init_features", "expected an integer >= 10");
  require(min_init_stereo >= 10 && min_init_stereo <= min_init_features, "min_init_stereo",
          "expected an integer in [10, min_init_features]");
  require(motion_model_radius_px >= 1 && motion_model_radius_px <= 100, "motion_model_radius_px",
          "expected an integer in [1, 100] px");
  require(min_motion_model_matches >= 5, "min_motion_model_matches", "expected an integer >= 5");
  require(min_frame_inliers >= 3, "min_frame_inliers", "expected an integer >= 3");
  require(min_reference_matches >= min_frame_inliers, "min_reference_matches", "expected an integer >= min_frame_inliers");
  require(reference_ratio > 0 && reference_ratio <= 1, "reference_ratio", "expected a ratio in (0, 1]");
  require(local_map_radius > 0 && local_map_radius <= 20, "local_map_radius", "expected a factor in (0, 20]");
  require(min_local_map_inliers >= min_frame_inliers, "min_local_map_inliers", "expected an integer >= min_frame_inliers");
  require(max_local_keyframes >= 2, "max_local_keyframes", "expected an integer >= 2");
  require(keyframe_max_frames >= 0, "keyframe_max_frames", "expected an integer >= 0 (0: the frame rate)");
  require(keyframe_min_frames >= 0, "keyframe_min_frames", "expected an integer >= 0");
  require(keyframe_ref_ratio > 0 && keyframe_ref_ratio <= 1, "keyframe_ref_ratio", "expected a ratio in (0, 1]");
  require(keyframe_close_tracked >= 0, "keyframe_close_tracked", "expected an integer >= 0");
  require(keyframe_close_untracked >= 0, "keyframe_close_untracked", "expected an integer >= 0");
  require(keyframe_max_new_points >= 0, "keyframe_max_new_points", "expected an integer >= 0");
  require(keyframe_revisit_distance_m >= 0 && keyframe_revisit_distance_m <= 10, "keyframe_revisit_distance_m",
          "expected a distance in [0, 10] m (0: off)");
  require(keyframe_revisit_angle_deg > 0 && keyframe_revisit_angle_deg <= 90, "keyframe_revisit_angle_deg",
          "expected an angle in (0, 90] degrees");
  require(keyframe_revisit_shared > 0 && keyframe_revisit_shared <= 1, "keyframe_revisit_shared",
          "expected a ratio in (0, 1]");
  require(keyframe_revisit_min_age_s >= 0, "keyframe_revisit_min_age_s", "expected a time >= 0 s");
  require(keyframe_stop_speed_mps >= 0 && keyframe_stop_speed_mps <= 10, "keyframe_stop_speed_mps",
          "expected a speed in [0, 10] m/s");
  require(keyframe_stop_distance_m >= 0 && keyframe_stop_distance_m <= 100, "keyframe_stop_distance_m",
          "expected a distance in [0, 100] m (0: off)");
  require(reset_max_keyframes >= 0, "reset_max_keyframes", "expected an integer >= 0");
  require(reset_after_lost_frames >= 1, "reset_after_lost_frames", "expected an integer >= 1");
}

std::string TrackingConfig::describe() const {
  char buf[1024];
  std::snprintf(buf, sizeof(buf),
                "tracking: close points < %.0f baselines, init > %d features (>= %d stereo), motion model window %d px "
                "(>= %d matches), >= %d frame inliers, reference matching ratio %.2f (>= %d), local map window x%.1f "
                "(>= %d inliers, <= %d keyframes), keyframe every <= %d frames (0 = rate), ref ratio %.2f, close "
                "%d/%d, >= %d new points; revisits: none within %.2f m / %.0f deg of a keyframe >= %.1f s old "
                "sharing >= %.2f of the inliers; one where it stops (<= %.2f m/s) >= %.2f m from the last (0: off); "
                "reset after %d lost frames with <= %d keyframes",
                close_depth_baselines, min_init_features, min_init_stereo, motion_model_radius_px, min_motion_model_matches,
                min_frame_inliers, reference_ratio, min_reference_matches, local_map_radius, min_local_map_inliers,
                max_local_keyframes, keyframe_max_frames, keyframe_ref_ratio, keyframe_close_tracked,
                keyframe_close_untracked, keyframe_max_new_points, keyframe_revisit_distance_m, keyframe_revisit_angle_deg,
                keyframe_revisit_min_age_s, keyframe_revisit_shared, keyframe_stop_speed_mps, keyframe_stop_distance_m,
                reset_after_lost_frames, reset_max_keyframes);
  return buf;
}

void LocalMappingConfig::validate(const std::string& source) const {
  const Checker require{source, "mapping"};
  require(queue_capacity >= 1 && queue_capacity <= 100, "queue_capacity", "expected an integer in [1, 100]");
  require(triangulation_neighbours >= 1, "triangulation_neighbours", "expected an integer >= 1");
  require(fusion_neighbours >= 0, "fusion_neighbours", "expected an integer >= 0");
  require(fusion_second_order >= 0, "fusion_second_order", "expected an integer >= 0");
  require(fusion_radius > 0 && fusion_radius <= 20, "fusion_radius", "expected a factor in (0, 20]");
  require(local_ba_iterations_first >= 0, "local_ba_iterations_first", "expected an integer >= 0");
  require(local_ba_iterations_second >= 0, "local_ba_iterations_second", "expected an integer >= 0");
  require(max_local_ba_keyframes >= 1, "max_local_ba_keyframes", "expected an integer >= 1");
  require(map_point_min_found_ratio >= 0 && map_point_min_found_ratio <= 1, "map_point_min_found_ratio",
          "expected a ratio in [0, 1]");
  require(map_point_min_observations >= 1, "map_point_min_observations", "expected an integer >= 1");
  require(keyframe_redundancy > 0 && keyframe_redundancy <= 1, "keyframe_redundancy", "expected a ratio in (0, 1]");
  require(keyframe_redundancy_observers >= 1, "keyframe_redundancy_observers", "expected an integer >= 1");
  require(max_keyframes == 0 || max_keyframes >= 10, "max_keyframes", "expected 0 (no cap) or an integer >= 10");
}

std::string LocalMappingConfig::describe() const {
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "mapping: queue %d keyframes, triangulation with %d neighbours, fusion %d+%d neighbours window x%.1f, "
                "local BA %d+%d iterations over <= %d keyframes, point culling found/visible < %.2f or < %d "
                "observers, keyframe culling %.0f %% seen by >= %d others, keyframe cap %d (0 = none)",
                queue_capacity, triangulation_neighbours, fusion_neighbours, fusion_second_order, fusion_radius,
                local_ba_iterations_first, local_ba_iterations_second, max_local_ba_keyframes,
                map_point_min_found_ratio, map_point_min_observations, keyframe_redundancy * 100.0,
                keyframe_redundancy_observers, max_keyframes);
  return buf;
}

void OptimizerConfig::validate(const std::string& source) const {
  const Checker require{source, "optimizer"};
  require(chi2_mono > 0, "chi2_mono", "expected a positive chi-square threshold (2 DOF)");
  require(chi2_stereo > 0, "chi2_stereo", "expected a positive chi-square threshold (3 DOF)");
  require(motion_rounds >= 1 && motion_rounds <= 20, "motion_rounds", "expected an integer in [1, 20]");
  require(motion_iterations >= 1 && motion_iterations <= 100, "motion_iterations", "expected an integer in [1, 100]");
  require(motion_robust_rounds >= 0 && motion_robust_rounds <= motion_rounds, "motion_robust_rounds",
          "expected an integer in [0, motion_rounds]");
}

std::string OptimizerConfig::describe() const {
  char buf[256];
  std::snprintf(buf, sizeof(buf),
                "optimizer: chi2 mono %.3f stereo %.3f, motion-only BA %d rounds x %d iterations (Huber in the first "
                "%d), local BA %s",
                chi2_mono, chi2_stereo, motion_rounds, motion_iterations, motion_robust_rounds,
                local_ba_dense_schur ? "DENSE_SCHUR" : "SPARSE_SCHUR");
  return buf;
}

void RelocalisationConfig::validate(const std::string& source) const {
  const Checker require{source, "relocalisation"};
  require(max_candidates >= 1, "max_candidates", "expected an integer >= 1");
  require(min_bow_matches >= 4, "min_bow_matches", "expected an integer >= 4");
  require(bow_ratio > 0 && bow_ratio <= 1, "bow_ratio", "expected a ratio in (0, 1]");
  require(pnp_iterations >= 1 && pnp_iterations <= 100000, "pnp_iterations", "expected an integer in [1, 100000]");
  require(pnp_reprojection_px > 0 && pnp_reprojection_px <= 50, "pnp_reprojection_px", "expected a number in (0, 50] px");
  require(min_pnp_inliers >= 4, "min_pnp_inliers", "expected an integer >= 4");
  require(min_inliers >= min_pnp_inliers, "min_inliers", "expected an integer >= min_pnp_inliers");
  require(projection_radius_px > 0 && projection_radius_px <= 100, "projection_radius_px", "expected a number in (0, 100] px");
}

std::string RelocalisationConfig::describe() const {
  char buf[384];
  std::snprintf(buf, sizeof(buf),
                "relocalisation: <= %d BoW candidates, >= %d BoW matches (ratio %.2f), EPnP RANSAC %d iterations "
                "%.1f px (>= %d inliers), success with >= %d inliers after motion-only BA and a %.0f px projection "
                "search",
                max_candidates, min_bow_matches, bow_ratio, pnp_iterations, pnp_reprojection_px, min_pnp_inliers,
                min_inliers, projection_radius_px);
  return buf;
}

void LoopClosingConfig::validate(const std::string& source) const {
  const Checker require{source, "loop_closing"};
  require(queue_capacity >= 1 && queue_capacity <= 1000, "queue_capacity", "expected an integer in [1, 1000]");
  require(min_keyframes_between_loops >= 0, "min_keyframes_between_loops", "expected an integer >= 0");
  require(consistency >= 0 && consistency <= 20, "consistency", "expected an integer in [0, 20]");
  require(covisible_consistency >= 0 && covisible_consistency <= 5, "covisible_consistency", "expected an integer in [0, 5]");
  require(confirmation_max_m > 0, "confirmation_max_m", "expected a distance > 0 m");
  require(confirmation_max_deg > 0, "confirmation_max_deg", "expected an angle > 0 deg");
  require(bow_ratio > 0 && bow_ratio <= 1, "bow_ratio", "expected a ratio in (0, 1]");
  require(min_bow_matches >= 3, "min_bow_matches", "expected an integer >= 3");
  require(ransac_iterations >= 1 && ransac_iterations <= 100000, "ransac_iterations", "expected an integer in [1, 100000]");
  require(ransac_chi2 > 0, "ransac_chi2", "expected a positive chi-square threshold");
  require(min_ransac_inliers >= 3, "min_ransac_inliers", "expected an integer >= 3");
  require(projection_radius_px > 0 && projection_radius_px <= 100, "projection_radius_px", "expected a number in (0, 100] px");
  require(min_refined_inliers >= 3, "min_refined_inliers", "expected an integer >= 3");
  require(min_total_matches >= min_refined_inliers, "min_total_matches", "expected an integer >= min_refined_inliers");
  require(max_correction_m >= 0, "max_correction_m", "expected a distance >= 0 m (0: no limit)");
  require(essential_min_weight >= 15, "essential_min_weight", "expected an integer >= 15 (shared map points)");
  require(pose_graph_iterations >= 1 && pose_graph_iterations <= 1000, "pose_graph_iterations", "expected an integer in [1, 1000]");
  require(global_ba_iterations >= 1 && global_ba_iterations <= 1000, "global_ba_iterations", "expected an integer in [1, 1000]");
}

std::string LoopClosingConfig::describe() const {
  char buf[512];
  std::snprintf(buf, sizeof(buf),
                "loop closing: %s, queue %d, >= %d keyframes apart, %d consistent groups or %d confirming covisible "
                "keyframes (%.3f m, %.1f deg), BoW >= %d matches (ratio "
                "%.2f), SE(3) RANSAC %d iterations chi2 %.2f (>= %d inliers), refined >= %d, >= %d matches with the "
                "loop neighbourhood, correction limit %.2f m (0 = none), essential graph covisibility >= %d, pose "
                "graph %d iterations, global BA %s (%d iterations, background thread)",
                enabled ? "on" : "off", queue_capacity, min_keyframes_between_loops, consistency, covisible_consistency,
                confirmation_max_m, confirmation_max_deg, min_bow_matches,
                bow_ratio, ransac_iterations, ransac_chi2, min_ransac_inliers, min_refined_inliers, min_total_matches,
                max_correction_m, essential_min_weight, pose_graph_iterations, global_ba ? "on" : "off",
                global_ba_iterations);
  return buf;
}

void SlamConfig::validate(const std::string& source) const {
  tracking.validate(source);
  mapping.validate(source);
  optimizer.validate(source);
  relocalisation.validate(source);
  loop_closing.validate(source);
}

std::vector<std::string> SlamConfig::describe() const {
  return {tracking.describe(), mapping.describe(), optimizer.describe(), relocalisation.describe(),
          loop_closing.describe()};
}

SlamConfig load_slam_config(const std::string& path) {
  const stereo::ParamsReader in(path);
  in.check_sections({"tracking", "mapping", "optimizer", "relocalisation", "loop_closing"});
  SlamConfig c;

  TrackingConfig& t = c.tracking;
  in.check_keys("tracking",
                {"close_depth_baselines", "min_init_features", "min_init_stereo", "motion_model_radius_px", "min_motion_model_matches",
                 "min_frame_inliers", "min_reference_matches", "reference_ratio", "bow_matching", "local_map_radius",
                 "min_local_map_inliers", "max_local_keyframes", "keyframe_max_frames", "keyframe_min_frames",
                 "keyframe_ref_ratio", "keyframe_close_tracked", "keyframe_close_untracked",
                 "keyframe_max_new_points", "keyframe_revisit_distance_m", "keyframe_revisit_angle_deg",
                 "keyframe_revisit_shared", "keyframe_revisit_min_age_s", "keyframe_stop_speed_mps",
                 "keyframe_stop_distance_m", "reset_max_keyframes", "reset_after_lost_frames"});
  in.read("tracking", "close_depth_baselines", t.close_depth_baselines, "a number (baselines)");
  in.read("tracking", "min_init_features", t.min_init_features, "an integer");
  in.read("tracking", "min_init_stereo", t.min_init_stereo, "an integer");
  in.read("tracking", "motion_model_radius_px", t.motion_model_radius_px, "an integer (px)");
  in.read("tracking", "min_motion_model_matches", t.min_motion_model_matches, "an integer");
  in.read("tracking", "min_frame_inliers", t.min_frame_inliers, "an integer");
  in.read("tracking", "min_reference_matches", t.min_reference_matches, "an integer");
  in.read("tracking", "reference_ratio", t.reference_ratio, "a number (ratio)");
  in.read("tracking", "bow_matching", t.bow_matching, "true or false");
  in.read("tracking", "local_map_radius", t.local_map_radius, "a number (factor)");
  in.read("tracking", "min_local_map_inliers", t.min_local_map_inliers, "an integer");
  in.read("tracking", "max_local_keyframes", t.max_local_keyframes, "an integer");
  in.read("tracking", "keyframe_max_frames", t.keyframe_max_frames, "an integer (frames)");
  in.read("tracking", "keyframe_min_frames", t.keyframe_min_frames, "an integer (frames)");
  in.read("tracking", "keyframe_ref_ratio", t.keyframe_ref_ratio, "a number (ratio)");
  in.read("tracking", "keyframe_close_tracked", t.keyframe_close_tracked, "an integer");
  in.read("tracking", "keyframe_close_untracked", t.keyframe_close_untracked, "an integer");
  in.read("tracking", "keyframe_max_new_points", t.keyframe_max_new_points, "an integer");
  in.read("tracking", "keyframe_revisit_distance_m", t.keyframe_revisit_distance_m, "a number (m)");
  in.read("tracking", "keyframe_revisit_angle_deg", t.keyframe_revisit_angle_deg, "a number (degrees)");
  in.read("tracking", "keyframe_revisit_shared", t.keyframe_revisit_shared, "a number (ratio)");
  in.read("tracking", "keyframe_revisit_min_age_s", t.keyframe_revisit_min_age_s, "a number (s)");
  in.read("tracking", "keyframe_stop_speed_mps", t.keyframe_stop_speed_mps, "a number (m/s)");
  in.read("tracking", "keyframe_stop_distance_m", t.keyframe_stop_distance_m, "a number (m)");
  in.read("tracking", "reset_max_keyframes", t.reset_max_keyframes, "an integer");
  in.read("tracking", "reset_after_lost_frames", t.reset_after_lost_frames, "an integer (frames)");

  LocalMappingConfig& m = c.mapping;
  in.check_keys("mapping", {"queue_capacity", "triangulation_neighbours", "triangulation_bow", "fusion_neighbours", "fusion_second_order",
                            "fusion_radius", "local_ba_iterations_first", "local_ba_iterations_second",
                            "max_local_ba_keyframes", "map_point_min_found_ratio", "map_point_min_observations",
                            "keyframe_redundancy", "keyframe_redundancy_observers", "max_keyframes"});
  in.read("mapping", "queue_capacity", m.queue_capacity, "an integer (keyframes)");
  in.read("mapping", "triangulation_neighbours", m.triangulation_neighbours, "an integer");
  in.read("mapping", "triangulation_bow", m.triangulation_bow, "true or false");
  in.read("mapping", "fusion_neighbours", m.fusion_neighbours, "an integer");
  in.read("mapping", "fusion_second_order", m.fusion_second_order, "an integer");
  in.read("mapping", "fusion_radius", m.fusion_radius, "a number (factor)");
  in.read("mapping", "local_ba_iterations_first", m.local_ba_iterations_first, "an integer");
  in.read("mapping", "local_ba_iterations_second", m.local_ba_iterations_second, "an integer");
  in.read("mapping", "max_local_ba_keyframes", m.max_local_ba_keyframes, "an integer");
  in.read("mapping", "map_point_min_found_ratio", m.map_point_min_found_ratio, "a number (ratio)");
  in.read("mapping", "map_point_min_observations", m.map_point_min_observations, "an integer");
  in.read("mapping", "keyframe_redundancy", m.keyframe_redundancy, "a number (ratio)");
  in.read("mapping", "keyframe_redundancy_observers", m.keyframe_redundancy_observers, "an integer");
  in.read("mapping", "max_keyframes", m.max_keyframes, "an integer");

  OptimizerConfig& o = c.optimizer;
  in.check_keys("optimizer", {"chi2_mono", "chi2_stereo", "motion_rounds", "motion_iterations", "motion_robust_rounds",
                              "local_ba_dense_schur"});
  in.read("optimizer", "chi2_mono", o.chi2_mono, "a number");
  in.read("optimizer", "chi2_stereo", o.chi2_stereo, "a number");
  in.read("optimizer", "motion_rounds", o.motion_rounds, "an integer");
  in.read("optimizer", "motion_iterations", o.motion_iterations, "an integer");
  in.read("optimizer", "motion_robust_rounds", o.motion_robust_rounds, "an integer");
  in.read("optimizer", "local_ba_dense_schur", o.local_ba_dense_schur, "true or false");

  RelocalisationConfig& r = c.relocalisation;
  in.check_keys("relocalisation", {"max_candidates", "min_bow_matches", "bow_ratio", "pnp_iterations",
                                   "pnp_reprojection_px", "min_pnp_inliers", "min_inliers", "projection_radius_px"});
  in.read("relocalisation", "max_candidates", r.max_candidates, "an integer");
  in.read("relocalisation", "min_bow_matches", r.min_bow_matches, "an integer");
  in.read("relocalisation", "bow_ratio", r.bow_ratio, "a number (ratio)");
  in.read("relocalisation", "pnp_iterations", r.pnp_iterations, "an integer");
  in.read("relocalisation", "pnp_reprojection_px", r.pnp_reprojection_px, "a number (px)");
  in.read("relocalisation", "min_pnp_inliers", r.min_pnp_inliers, "an integer");
  in.read("relocalisation", "min_inliers", r.min_inliers, "an integer");
  in.read("relocalisation", "projection_radius_px", r.projection_radius_px, "a number (px)");

  LoopClosingConfig& l = c.loop_closing;
  in.check_keys("loop_closing",
                {"enabled", "queue_capacity", "min_keyframes_between_loops", "consistency", "covisible_consistency",
                 "confirmation_max_m", "confirmation_max_deg", "bow_ratio",
                 "min_bow_matches", "ransac_iterations", "ransac_chi2", "min_ransac_inliers", "projection_radius_px",
                 "min_refined_inliers", "min_total_matches", "max_correction_m", "essential_min_weight",
                 "pose_graph_iterations", "global_ba", "global_ba_iterations"});
  in.read("loop_closing", "enabled", l.enabled, "true or false");
  in.read("loop_closing", "queue_capacity", l.queue_capacity, "an integer (keyframes)");
  in.read("loop_closing", "min_keyframes_between_loops", l.min_keyframes_between_loops, "an integer (keyframes)");
  in.read("loop_closing", "consistency", l.consistency, "an integer");
  in.read("loop_closing", "covisible_consistency", l.covisible_consistency, "an integer");
  in.read("loop_closing", "confirmation_max_m", l.confirmation_max_m, "a number (m)");
  in.read("loop_closing", "confirmation_max_deg", l.confirmation_max_deg, "a number (deg)");
  in.read("loop_closing", "bow_ratio", l.bow_ratio, "a number (ratio)");
  in.read("loop_closing", "min_bow_matches", l.min_bow_matches, "an integer");
  in.read("loop_closing", "ransac_iterations", l.ransac_iterations, "an integer");
  in.read("loop_closing", "ransac_chi2", l.ransac_chi2, "a number");
  in.read("loop_closing", "min_ransac_inliers", l.min_ransac_inliers, "an integer");
  in.read("loop_closing", "projection_radius_px", l.projection_radius_px, "a number (px)");
  in.read("loop_closing", "min_refined_inliers", l.min_refined_inliers, "an integer");
  in.read("loop_closing", "min_total_matches", l.min_total_matches, "an integer");
  in.read("loop_closing", "max_correction_m", l.max_correction_m, "a number (m)");
  in.read("loop_closing", "essential_min_weight", l.essential_min_weight, "an integer");
  in.read("loop_closing", "pose_graph_iterations", l.pose_graph_iterations, "an integer");
  in.read("loop_closing", "global_ba", l.global_ba, "true or false");
  in.read("loop_closing", "global_ba_iterations", l.global_ba_iterations, "an integer");

  c.validate(path);
  return c;
}

}  // namespace agvslam::slam
