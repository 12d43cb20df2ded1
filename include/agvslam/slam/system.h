#pragma once
// The SLAM system facade (paper 004 III.C: ORB-SLAM2's framework on the static part of the image).
//
//   SystemConfig config;                                  // + config.vocabulary = load_vocabulary(place config)
//   System slam(calibration, config);
//   TrackResult r = slam.track_stereo(t_ns, left, right, dynamic_mask);   // caller's thread = tracking thread
//   if (r.state == TrackingState::kOk) use(r.T_w_c);
//
// Threads: the caller's thread tracks (ORB extraction outside the dilated dynamic mask, stereo matching, pose);
// the local mapper and the loop closer run in their own threads (SystemConfig::threaded_mapping), fed through
// bounded queues; the loop closer's global bundle adjustment runs in a further background thread and never holds
// the map while it solves. With threaded_mapping = false all of it runs inside track_stereo (deterministic).
//
// A lost frame gives state kLost and no pose (r.T_w_c is the identity and pose_valid is false), never a guessed
// pose; the following frames relocalise with the bag-of-words keyframe database (needs config.vocabulary). Lost
// for longer than slam.tracking.new_map_after_lost_s, a new map is started from the current stereo frame
// (r.map_id counts up, r.counts.new_map is set); the old map's trajectory is kept, and the old map itself is saved
// to config.earlier_maps_folder when one is set (not kept in memory: no relocalisation into it, no merge).
// request_reset() empties the map at the next frame; shutdown() stops the threads (also done by the destructor).
//
// Saved maps (for agvslamd and agvslam-run; file format in map_io.h):
//   slam.save_map(path);                      // any time; waits for local mapping and loop closing to settle,
//                                             // writes atomically (temporary file + fsync + rename)
//   slam.load_map(path, MapMode::kLocalisation);   // before or between frames (not concurrently with
//                                             // track_stereo); replaces the map, the next frames relocalise in it
//   slam.set_mode(MapMode::kMapping);         // switch at any time between frames
// MapMode::kLocalisation tracks against the map without changing it (no keyframes, so no local mapping and no
// loop closing); MapMode::kMapping extends it (new keyframes, loops closed against the loaded part). Errors:
// save_map and load_map throw InputError(path, field, expected) for an unwritable folder, a missing, truncated or
// corrupt file, another format version, another vocabulary or another camera; a failed load leaves the current
// map and mode untouched, a failed save leaves the previous file untouched. The map's world frame is the saved
// map's (its first keyframe's camera), so poses after a restart come back in the same frame.

#include <cstdint>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/trajectory.h"
#include "agvslam/features/orb_extractor.h"
#include "agvslam/features/stereo_matcher.h"
#include "agvslam/place/place_config.h"
#include "agvslam/place/vocabulary.h"
#include "agvslam/slam/local_mapping.h"
#include "agvslam/slam/loop_closing.h"
#include "agvslam/slam/map.h"
#include "agvslam/slam/map_io.h"
#include "agvslam/slam/place_recognition.h"
#include "agvslam/slam/slam_config.h"
#include "agvslam/slam/tracking.h"

namespace agvslam::slam {

struct SystemConfig {
  SlamConfig slam;
  features::OrbExtractorConfig orb;
  features::StereoMatcherConfig stereo;
  double frame_rate_hz = 20;     // the camera's rate (keyframe spacing: at least one per second)
  bool threaded_mapping = true;  // false: each keyframe is mapped (and loops closed) in track_stereo before it
                                 // returns (deterministic)
  // Bag-of-words vocabulary (load_vocabulary). Null: no relocalisation by place recognition, no loop closing,
  // brute-force matching; maps are saved with vocabulary identity 0.
  std::shared_ptr<const place::Vocabulary> vocabulary;
  int direct_index_level = 2;  // params/place.yaml vocabulary.direct_index_level
  // A folder: when a long loss starts a new map (slam.tracking.new_map_after_lost_s), the map left behind is saved
  // there as map_<its map_id>.agvmap (atomically, as save_map) for later loading; "": it is dropped.
  std::string earlier_maps_folder;
  // TEST ONLY: LocalMapping::set_test_step_delay_ms (a slower computer); not in any YAML. Never set on a vehicle.
  double test_mapping_step_delay_ms = 0;
};

// Loads the vocabulary that a place configuration names (InputError naming the file for a bad one).
std::shared_ptr<const place::Vocabulary> load_vocabulary(const place::PlaceConfig& place);

enum class MapMode { kMapping, kLocalisation };
const char* to_string(MapMode mode);
// "map" / "mapping" -> kMapping, "localise" / "localisation" / "localization" -> kLocalisation; InputError(option,
// text, expected) otherwise.
MapMode parse_map_mode(const std::string& text, const std::string& option = "--mode");

struct TrackResult {
  int64_t t_ns = 0;
  uint64_t frame_id = 0;
  TrackingState state = TrackingState::kInitialising;
  bool pose_valid = false;        // state == kOk
  SE3d T_w_c = SE3d::Identity();  // left camera in the world (the first keyframe's camera); identity when invalid
  TrackingCounts counts;
  TrackTimings timings;
  std::size_t keyframes = 0;  // in the map after this frame
  std::size_t map_points = 0;
  std::size_t mapping_queue = 0;  // keyframes waiting for the local mapper
  uint64_t loops_closed = 0;      // loops closed so far
  // Which map the pose is in: 0 from the start (or the loaded map); +1 each time tracking was lost for
  // tracking.new_map_after_lost_s and a new map was started (its world frame is the camera at that frame, so poses
  // jump: the vehicle must not compare them with earlier ones). counts.new_map marks the frame that starts one.
  uint32_t map_id = 0;
  bool global_ba_running = false;
  // Level-0 pixel positions (left image) of the keypoints the pose rests on: the map point inliers of this frame
  // (empty unless the state is ok). Tools score them against ground-truth masks: how much of the pose leaned on
  // moving objects.
  std::vector<cv::Point2f> inlier_keypoints_px;
};

struct MapSaveStats {
  std::size_t keyframes = 0, map_points = 0, bytes = 0;
  double wait_ms = 0;    // waiting for local mapping / loop closing to settle
  double encode_ms = 0;  // with the map locked
  double write_ms = 0;   // temporary file, fsync, rename
};

struct MapLoadStats {
  std::size_t keyframes = 0, map_points = 0, bytes = 0;
  double read_ms = 0, decode_ms = 0, bow_ms = 0;
};

class System {
 public:
  System(const StereoCalibration& calibration, const SystemConfig& config = {});
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  // left/right: rectified CV_8UC1 of the calibration's size; dynamic_mask: CV_8UC1 of the same size (non-zero =
  // moving object, no features there; dilated by the extractor) or empty.
  TrackResult track_stereo(int64_t t_ns, const cv::Mat& left, const cv::Mat& right, const cv::Mat& dynamic_mask);

  void request_reset();
  void shutdown();

  // Saved maps (see the top of this file). hooks: fault injection for tests.
  MapSaveStats save_map(const std::string& path, const MapWriteHooks& hooks = {});
  MapLoadStats load_map(const std::string& path, MapMode mode);
  void set_mode(MapMode mode);
  MapMode mode() const { return mode_; }

  // The trajectory of every tracked frame, each pose expressed relative to its reference keyframe and composed
  // with that keyframe's current (bundle-adjusted) pose, as ORB-SLAM2 saves it. Frames that were not tracked are
  // absent. Frames of earlier maps (new_map_after_lost_s) keep the poses they had when their map was left, in that
  // map's frame; map_ids (optional) receives the map of each pose.
  Trajectory trajectory(std::vector<uint32_t>* map_ids = nullptr);
  uint32_t map_id() const { return map_id_; }
  // Files of the maps left behind (SystemConfig::earlier_maps_folder) and the errors of those that could not be
  // written (InputError texts; tracking goes on).
  std::vector<std::string> earlier_map_files() const;
  std::vector<std::string> earlier_map_errors() const;
  // Waits for the local mapper to finish the queued keyframes.
  void wait_for_mapping();

  Map& map() { return map_; }
  LocalMapping& local_mapping() { return *mapper_; }
  LocalMappingStats mapping_stats() const { return mapper_->stats(); }
  // Map points retired since the start because the object they lay on moved (point_retirement.h), by reason.
  RetirementCounts retirement_counts() const;
  // Loop closing (null without a vocabulary or with slam.loop_closing.enabled = false).
  LoopClosing* loop_closing() { return loop_.get(); }
  LoopClosingStats loop_stats() const { return loop_ ? loop_->stats() : LoopClosingStats{}; }
  const std::shared_ptr<PlaceRecognition>& place_recognition() const { return place_; }
  const FrameGeometryPtr& geometry() const { return geometry_; }
  const SystemConfig& config() const { return config_; }
  std::vector<std::string> describe() const;

 private:
  void reset_now();
  // Lost for too long: the current map's trajectory is frozen, the map cleared and the counter moved on.
  void start_new_map();
  // After a tracked frame: its pose, pose inliers and trajectory entry into r.
  void take_pose(TrackResult& r);
  // Waits until local mapping and loop closing are idle (threaded) or runs their queues (inline).
  void settle();
  MapFileContext file_context() const;

  SystemConfig config_;
  StereoCalibration calibration_;
  FrameGeometryPtr geometry_;
  Map map_;
  std::shared_ptr<PlaceRecognition> place_;
  std::unique_ptr<LocalMapping> mapper_;
  std::unique_ptr<LoopClosing> loop_;
  std::unique_ptr<Tracking> tracking_;
  MapMode mode_ = MapMode::kMapping;
  features::OrbExtractor extractor_;
  features::StereoMatcher stereo_matcher_;
  features::KeypointSet keypoints_;
  features::StereoDepth depth_;
  Frame frame_;
  uint64_t next_frame_id_ = 0;
  bool reset_requested_ = false;
  std::mutex reset_mutex_;
  bool shut_down_ = false;
  mutable std::mutex retired_mutex_;
  RetirementCounts retired_;

  struct TrajectoryEntry {
    int64_t t_ns;
    uint64_t reference_kf_id;
    SE3d T_c_r;
  };
  std::vector<TrajectoryEntry> trajectory_;  // the current map's frames
  uint32_t map_id_ = 0;
  Trajectory earlier_maps_trajectory_;  // frames of maps left behind, with their poses when they were left
  std::vector<uint32_t> earlier_maps_ids_;
  mutable std::mutex earlier_files_mutex_;
  std::vector<std::string> earlier_map_files_, earlier_map_errors_;
};

}  // namespace agvslam::slam
