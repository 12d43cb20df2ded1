#pragma once
// The SLAM system facade (paper 004 III.C: ORB-SLAM2's framework on the static part of the image).
//
//   System slam(calibration, config);
//   TrackResult r = slam.track_stereo(t_ns, left, right, dynamic_mask);   // caller's thread = tracking thread
//   if (r.state == TrackingState::kOk) use(r.T_w_c);
//
// Threads: the caller's thread tracks (ORB extraction outside the dilated dynamic mask, stereo matching, pose);
// the local mapper runs in its own thread (SystemConfig::threaded_mapping) and receives keyframes through a
// bounded queue; the loop-closing thread and the keyframe database of issue 5 attach to the mapper's keyframe
// sink (LocalMapping::set_keyframe_sink) and to Map / KeyFrame::bow.
//
// A lost frame gives state kLost and no pose (r.T_w_c is the identity and pose_valid is false), never a guessed
// pose. request_reset() empties the map at the next frame; shutdown() stops the mapper (also done by the
// destructor).

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
#include "agvslam/slam/local_mapping.h"
#include "agvslam/slam/map.h"
#include "agvslam/slam/place_recognition.h"
#include "agvslam/slam/slam_config.h"
#include "agvslam/slam/tracking.h"

namespace agvslam::slam {

struct SystemConfig {
  SlamConfig slam;
  features::OrbExtractorConfig orb;
  features::StereoMatcherConfig stereo;
  double frame_rate_hz = 20;     // the camera's rate (keyframe spacing: at least one per second)
  bool threaded_mapping = true;  // false: each keyframe is mapped in track_stereo before it returns (deterministic)
};

struct TrackResult {
  int64_t t_ns = 0;
  uint64_t frame_id = 0;
  TrackingState state = TrackingState::kInitialising;
  bool pose_valid = false;       // state == kOk
  SE3d T_w_c = SE3d::Identity(); // left camera in the world (the first keyframe's camera); identity when invalid
  TrackingCounts counts;
  TrackTimings timings;
  std::size_t keyframes = 0;     // in the map after this frame
  std::size_t map_points = 0;
  std::size_t mapping_queue = 0; // keyframes waiting for the local mapper
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
  // Attaches issue 5's keyframe database (before the first frame): keyframes get BowData, loss is recovered
  // through its candidates.
  void set_place_recognition(const std::shared_ptr<PlaceRecognition>& place);

  // The trajectory of every tracked frame, each pose expressed relative to its reference keyframe and composed
  // with that keyframe's current (bundle-adjusted) pose, as ORB-SLAM2 saves it. Frames that were not tracked are
  // absent.
  Trajectory trajectory();
  // Waits for the local mapper to finish the queued keyframes.
  void wait_for_mapping();

  Map& map() { return map_; }
  LocalMapping& local_mapping() { return *mapper_; }
  LocalMappingStats mapping_stats() const { return mapper_->stats(); }
  const FrameGeometryPtr& geometry() const { return geometry_; }
  const SystemConfig& config() const { return config_; }
  std::vector<std::string> describe() const;

 private:
  void reset_now();

  SystemConfig config_;
  StereoCalibration calibration_;
  FrameGeometryPtr geometry_;
  Map map_;
  std::unique_ptr<LocalMapping> mapper_;
  std::unique_ptr<Tracking> tracking_;
  features::OrbExtractor extractor_;
  features::StereoMatcher stereo_matcher_;
  features::KeypointSet keypoints_;
  features::StereoDepth depth_;
  Frame frame_;
  uint64_t next_frame_id_ = 0;
  bool reset_requested_ = false;
  std::mutex reset_mutex_;
  bool shut_down_ = false;

  struct TrajectoryEntry {
    int64_t t_ns;
    uint64_t reference_kf_id;
    SE3d T_c_r;
  };
  std::vector<TrajectoryEntry> trajectory_;
};

}  // namespace agvslam::slam
