#pragma once
// The tracking stage (ORB-SLAM2's Tracking, stereo): stereo initialisation, constant-velocity motion model,
// reference-keyframe fallback, local-map tracking with motion-only BA, the keyframe decision and keyframe
// creation. Runs in the caller's thread; holds the Map's mutex while it works on a frame.
//
// Lost: when a frame cannot be tracked the state is kLost, no pose is given, and every following frame tries to
// relocalise (ORB-SLAM2's Relocalization): bag-of-words candidates from the place recognition, BoW matching, EPnP
// RANSAC on the candidates' map points, motion-only BA, a projection search for more matches; then the last
// reference keyframe and its neighbours (descriptor matching from their poses) before giving up again. A map of
// few keyframes is reset and initialised anew after tracking.reset_after_lost_frames (never a loaded map). A larger
// map lost for tracking.new_map_after_lost_s (frame time, counted on frames with enough features to start a map: a
// covered camera is waited out) asks for a new map (counts.new_map: System starts one from the same frame), so
// tracking is never lost for good.
//
// Keyframes: when one is due and local mapping's queue is full, tracking releases the map mutex and waits up to
// tracking.keyframe_queue_wait_ms for room (keyframe_queue_wait_weak_ms when the frame is near loss; a local BA in
// progress is interrupted) rather than skip it: skipping keyframe after keyframe leaves the map behind a fast camera
// until tracking is lost.
//
// Localisation only (set_localisation_only): frames are tracked against the map without changing its structure:
// no keyframes are created, so local mapping and loop closing get nothing. start_relocalising() (after a map is
// loaded) makes the next frame relocalise instead of initialising a new map.

#include <cstdint>
#include <memory>
#include <vector>

#include "agvslam/slam/frame.h"
#include "agvslam/slam/key_frame.h"
#include "agvslam/slam/matcher.h"
#include "agvslam/slam/optimizer.h"
#include "agvslam/slam/place_recognition.h"
#include "agvslam/slam/point_retirement.h"
#include "agvslam/slam/slam_config.h"

namespace agvslam::slam {

class Map;
class LocalMapping;

enum class TrackingState { kInitialising, kOk, kLost };
const char* to_string(TrackingState state);

// Per-stage wall-clock times of one frame in the tracking thread (ms).
struct TrackTimings {
  double extract_ms = 0;         // ORB on the left image (features module)
  double stereo_ms = 0;          // stereo matching at the keypoints (features module)
  double map_wait_ms = 0;        // waiting for the map mutex (held by the local mapper)
  double frame_ms = 0;           // motion model / reference keyframe / recovery, with its motion-only BA
  double local_map_ms = 0;       // local map update, projection search and motion-only BA
  double retire_ms = 0;          // retirement of map points that moved (point_retirement.h)
  double retire_cpu_ms = 0;      // ... its CPU time in this thread
  double keyframe_ms = 0;        // keyframe decision and creation (including keyframe_wait_ms)
  double keyframe_wait_ms = 0;   // waiting for room in local mapping's queue (tracking.keyframe_queue_wait_ms)
  double inline_mapping_ms = 0;  // local mapping run in this thread (SystemConfig::threaded_mapping = false only)
  double total_ms = 0;           // all of track_stereo (including inline mapping)
  double total_cpu_ms = 0;       // CPU time of the calling thread in track_stereo (what one core spends, whatever
                                 // else runs on the machine)
};

struct TrackingCounts {
  int features = 0;         // keypoints in the frame
  int stereo_features = 0;  // of which with stereo depth
  int frame_matches = 0;    // matches of the motion model / reference keyframe step
  const char* method = "";  // which step tracked the frame: init, motion_model, reference, relocalisation, recovery
  int inliers = 0;          // map point inliers after local-map tracking
  bool new_keyframe = false;
  bool recovered = false;             // tracked again after being lost (by relocalisation or recovery)
  int relocalisation_candidates = 0;  // BoW candidates tried while lost
  bool reset = false;                 // the map was reset on this frame
  bool new_map = false;               // lost for tracking.new_map_after_lost_s: a new map starts at this frame
  bool keyframe_waited = false;       // a keyframe was due with local mapping's queue full: tracking waited
  RetirementCounts retired;           // map points retired on this frame (point_retirement.h), by reason
};

class Tracking {
 public:
  Tracking(const SlamConfig& config, FrameGeometryPtr geometry, Map& map, LocalMapping& mapper, double frame_rate_hz);

  // Tracks `frame` (its features are set; its pose is overwritten). On success the frame has a pose. The
  // previous frame is kept internally (the frame object is swapped in, not copied). `images` (the frame's stereo
  // pair and dynamic mask; empty: none) let map points on objects that moved be retired; they are not kept.
  TrackingState track(Frame& frame, TrackTimings& timings, TrackingCounts& counts, const FrameImages& images = {});

  TrackingState state() const { return state_; }
  // Pose of the last frame (valid when state() == kOk).
  const Frame& last_frame() const { return last_frame_; }
  const KeyFramePtr& reference_keyframe() const { return reference_kf_; }
  // The last tracked frame's pose relative to its reference keyframe (last_frame().reference_keyframe).
  const SE3d& last_relative_pose() const { return last_T_c_r_; }

  // The keyframe database: relocalisation candidates while lost and BoW matching (set before the first frame).
  void set_place_recognition(std::shared_ptr<PlaceRecognition> place) { place_ = std::move(place); }

  // Forgets everything (the map must be cleared by the caller, with the mapper reset first).
  void reset();
  // After a map was loaded (map mutex held by the caller or no other thread running): forgets the frames, and the
  // next frames relocalise in the map (no initialisation, no reset of the map when lost).
  void start_relocalising();
  void set_localisation_only(bool value) { localisation_only_ = value; }
  bool localisation_only() const { return localisation_only_; }

  // Local map (for tests and statistics).
  std::size_t local_keyframe_count() const { return local_keyframes_.size(); }
  std::size_t local_point_count() const { return local_points_.size(); }

 private:
  // The frame has the keypoints and stereo depths a new map needs (tracking.min_init_features / min_init_stereo).
  bool can_initialise() const;
  bool stereo_initialisation();
  bool track_with_motion_model(int& matches);
  bool track_reference_keyframe(const KeyFrame& kf, const SE3d& T_c_w_guess, int& matches);
  bool recover(int& matches, TrackingCounts& counts);
  bool relocalise(int& matches, TrackingCounts& counts);
  void drop_outlier_matches();
  bool track_local_map(int& inliers);
  // Retirement of map points on objects that moved (mapping mode only: localisation leaves the map as it is).
  void retire_moved_points(const FrameImages& images, TrackingCounts& counts);
  void update_local_map();
  void search_local_points();
  int optimize_current_pose();
  int discard_outliers();
  enum class KeyframeNeed { kNo, kNow, kWhenQueueHasRoom };
  // kWhenQueueHasRoom: a keyframe is due but local mapping's queue is full (tracking waits for room, bounded).
  KeyframeNeed need_new_keyframe();
  // An older keyframe that already covers the current view (the revisit rule of TrackingConfig), or null.
  KeyFrame* revisited_keyframe() const;
  void create_new_keyframe();
  void check_replaced_in_last_frame();

  SlamConfig config_;
  FrameGeometryPtr geometry_;
  StereoIntrinsics intrinsics_;
  Map& map_;
  LocalMapping& mapper_;
  int max_frames_;
  int min_frames_;

  TrackingState state_ = TrackingState::kInitialising;
  Frame current_;
  Frame last_frame_;
  KeyFramePtr reference_kf_;
  uint64_t last_keyframe_frame_id_ = 0;
  Eigen::Vector3d last_keyframe_center_w_ = Eigen::Vector3d::Zero();  // where the last keyframe was made
  uint64_t last_recovery_frame_id_ = 0;
  SE3d last_T_c_r_ = SE3d::Identity();
  SE3d velocity_ = SE3d::Identity();  // T_c_l: last camera -> current camera
  bool has_velocity_ = false;
  int64_t velocity_dt_ns_ = 0;  // the time between the two frames velocity_ was measured on (0: unknown)
  // velocity_ scaled to the time since the last frame (a dropped frame doubles the motion to predict); velocity_
  // itself when either time is unknown.
  SE3d predicted_motion() const;
  int lost_frames_ = 0;
  int64_t lost_usable_ns_ = 0;  // time lost on frames that could start a map (new_map_after_lost_s)
  int64_t last_lost_t_ns_ = 0;  // the previous lost frame's stamp (0: none since the last tracked frame)
  int inliers_ = 0;
  int previous_inliers_ = 0;  // the last tracked frame's inliers (0: unknown, or a keyframe was made there)
  bool localisation_only_ = false;
  bool map_loaded_ = false;  // the map came from a file: never reset it

  // Rebuilt for every frame with the map mutex held and used only under it (raw pointers never outlive the lock).
  std::vector<KeyFrame*> local_keyframes_;
  std::vector<MapPoint*> local_points_;
  Matcher matcher_;
  std::shared_ptr<PlaceRecognition> place_;
  std::vector<PoseObservation> observations_;
  std::vector<int> observation_keypoint_;
  std::vector<uint8_t> observation_outlier_;
  std::vector<MapPointPtr> matches_;
  PointRetirement retirement_;
  std::vector<PointRetirement::Match> pose_matches_;  // every match of the last local-map pose optimisation
};

}  // namespace agvslam::slam
