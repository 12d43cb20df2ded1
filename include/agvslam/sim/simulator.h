#pragma once
// The synthetic stereo warehouse: scenario + renderer + sensor model, and the KITTI-layout writer.
//
// Frames and conventions:
//   map frame   internal (x east, y north, z up, floor z = 0);
//   camera      x right, y down, z forward; the right camera is at +baseline along the left camera's x;
//   world       the left camera frame at frame 0 (the first pose is the identity, as in KITTI);
//   poses.txt   T_w_cam0 per frame (3x4, row-major); times.txt seconds = frame / rate.
// Ground truth at pixel centres of the LEFT image: depth z along the optical axis, disparity
// fx * baseline / z (0 where nothing is hit, beyond max_depth_m or too close for 16 bits), the id of the actor
// seen there, the motion mask (255 where that actor is moving at that instant) and the semantic class of the
// surface (semantic_classes.h).

#include <cstdint>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/trajectory.h"
#include "agvslam/sim/renderer.h"
#include "agvslam/sim/scenario.h"
#include "agvslam/sim/sim_config.h"
#include "agvslam/sim/warehouse.h"

namespace agvslam::sim {

// An actor visible in the left image: bounding box of its visible pixels (inclusive).
struct VisibleObject {
  int id = 0;
  ActorClass cls = ActorClass::kPerson;
  bool moving = false;
  int x_min = 0, y_min = 0, x_max = 0, y_max = 0;
  int pixel_count = 0;
};

struct SimFrame {
  int index = 0;
  int64_t t_ns = 0;
  SE3d T_w_c = SE3d::Identity();  // left camera in the world frame
  double exposure_gain = 1.0;
  cv::Mat left, right;    // CV_8UC1
  cv::Mat disparity_u16;  // CV_16UC1: disparity * 256, 0 = none
  cv::Mat mask;           // CV_8UC1: 255 = pixel of a moving object
  cv::Mat instances;      // CV_8UC1: the id of the actor seen at each pixel (moving or not), 0 = none
  cv::Mat classes;        // CV_8UC1: the SemanticClass of each pixel (semantic_classes.h)
  std::vector<VisibleObject> objects;
  std::vector<DynamicObject> posed_objects;  // the actors as rendered
  CameraRender left_render, right_render;    // depth_m and object_id of each camera (pixel centres)
};

class Simulator {
 public:
  // Validates both (InputError naming the option or setting).
  Simulator(const SimConfig& config, const ScenarioOptions& options);
  // The renderer refers to the warehouse inside: not copyable or movable.
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  const SimConfig& config() const { return config_; }
  const Warehouse& warehouse() const { return warehouse_; }
  const Scenario& scenario() const { return scenario_; }
  const Renderer& renderer() const { return renderer_; }
  int frame_count() const { return scenario_.frames; }
  StereoCalibration calibration() const { return config_.calibration(); }
  CameraIntrinsics intrinsics() const;

  int64_t timestamp_ns(int frame) const;
  // Left camera pose in the map frame, and in the world frame (= left camera at frame 0).
  Eigen::Isometry3d T_map_cam(int frame) const;
  SE3d T_w_c(int frame) const { return T_w_map_ * T_map_cam(frame); }
  const Eigen::Isometry3d& T_w_map() const { return T_w_map_; }
  Trajectory ground_truth() const;
  // Global gain of frame `frame`: the sequence's exposure times its smooth variation.
  double exposure_gain(int frame) const;

  // The frames at which an actor moves, as inclusive [first, last] ranges.
  std::vector<std::pair<int, int>> moving_frames(const Actor& actor) const;
  // The actors posed at a frame: out[i] is actor i, then the trailers (a tugger's carts, with its id).
  void pose_objects(int frame, std::vector<DynamicObject>& out) const;
  // Renders both cameras and derives the ground truth; reuses `out`'s buffers.
  void render_frame(int frame, SimFrame& out, int threads = 1) const;

 private:
  SimConfig config_;
  Warehouse warehouse_;
  Scenario scenario_;
  Renderer renderer_;
  Eigen::Isometry3d T_w_map_ = Eigen::Isometry3d::Identity();
  uint64_t sensor_seed_ = 0;
  double exposure_phase_[2] = {0, 0};
  double exposure_base_ = 1.0;  // this sequence's exposure (SimConfig::exposure_spread)
  uint32_t vibration_seed_ = 0;
};

// Creates `dir` (and parents) and checks that files can be written there; throws
// InputError(option, dir, ...) otherwise.
void prepare_output_dir(const std::string& dir, const std::string& option = "--out");

struct WriteOptions {
  int threads = 1;
  // Called after each frame is written: (frames done, total).
  std::function<void(int, int)> progress;
};

// Writes the whole sequence in the KITTI layout:
//   image_0/ image_1/ NNNNNN.png (8-bit grey), disp_0/ NNNNNN.png (16-bit, disparity * 256, 0 = none),
//   mask_0/ NNNNNN.png (8-bit, 255 = moving object), instance_0/ NNNNNN.png (8-bit, the id of the actor seen at
//   each pixel, as in objects.txt, 0 = none: an object's own pixels where objects overlap), class_0/ NNNNNN.png
//   (8-bit, the SemanticClass id of each pixel, semantic_classes.h), calib.txt (labelled P0/P1), times.txt,
//   poses.txt,
//   objects.txt ("frame id class moving x_min y_min x_max y_max" per visible actor and frame),
//   odometry.txt (TUM: simulated wheel odometry with default WheelOdometryConfig errors, seeded by the scenario).
void write_sequence(const Simulator& sim, const std::string& out_dir, const WriteOptions& options = {});

// objects.txt header line (a comment describing the columns).
std::string objects_header();
std::string format_objects(int frame, const std::vector<VisibleObject>& objects);

}  // namespace agvslam::sim
