#pragma once
// Multi-frame motion test (beyond paper 004; paper 001's reprojection offsets over a longer baseline).
//
// The per-frame tests cannot see an object whose image barely changes between two frames: a person walking
// ahead of a forward-driving AGV at about its speed moves by a fraction of a pixel per frame
// relative to where a static point would be, below the tracking noise. Over 0.3-0.6 s the difference is
// several pixels and, in disparity, a pixel or more: the static scene comes closer (its disparity grows and
// it expands around the focus of expansion) while the walker keeps its distance.
//
// The detector keeps its LK tracks from frame to frame (TrackHistory holds each track's last observations:
// position and disparity). Each frame, a reference frame is chosen among the last max_frames: the newest at
// least min_frames back whose camera is at least min_translation_m away from the current one along the chain
// of per-frame ego-motions (the oldest allowed one when the vehicle stands still), with at most
// max_rotation_deg of rotation between them and at least min_points tracks observed in both. The motion
// between the two frames is estimated from those tracks (PnP on their 3-D reference positions, from the chained
// motion's inliers or by RANSAC as in the depth-consistency test), and a track is dynamic when its current
// position or disparity is off the prediction by more than a + b d (a adapts to the robust scale of this frame's
// residuals).
//
// Following tracks over frames instead of re-finding them in the reference image keeps the per-step motion
// small: re-localising a point 0.3-0.6 s back from the chained prediction aliases on repeated structure (the
// hole pattern of rack uprights) and drifts with the chain in turns, both of which look like motion. But a track
// that straddles an occlusion edge slides slowly over the frames, below the per-frame forward-backward check, and
// piles up with others on the edge. So each candidate (a track the test flags) is verified: its current patch is
// tracked by LK directly into the reference image, starting at the track's own reference position (close for a real
// mover, a few px off for a slid track), forward-backward checked; the candidate stays dynamic only when the position
// found, back-projected with the reference disparity, still misses the current position, and its disparity
// residual counts only when the position found is within verify_max_shift_px of the track's (the reference
// disparity was measured there). And a stereo mismatch in one frame (repetitive racking) gives a wrong depth that
// looks like motion over the longer baseline: only tracks whose disparity agreed with the ego-motion in every
// frame-to-frame step since the reference take part (chain_stereo_only; those the per-frame depth test flagged in
// a step must be off by chain_stereo_factor times the thresholds), or, with chain_stereo_only off, only tracks the
// per-frame test passed in every step.

#include <cstdint>
#include <deque>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "agvslam/core/camera.h"
#include "agvslam/core/se3.h"
#include "agvslam/dynamic/depth_test.h"
#include "agvslam/dynamic/epipolar.h"

namespace agvslam::dynamic {

// params/dynamic.yaml, section `multiframe`.
struct MultiFrameTestConfig {
  bool enabled = true;
  int max_frames = 12;             // history (frames); at 20 Hz 0.6 s
  int min_frames = 3;              // the reference is at least this many frames back
  double min_translation_m = 0.3;  // the newest reference this far from the current camera is used
  double max_rotation_deg = 6.0;   // references rotated more than this are not used
  int min_points = 20;             // tracks observed in both frames needed for the motion
  double min_disparity_px = 2.0;   // farther points are neither used nor tested
  double ransac_reprojection_px = 2.0;
  double a_reproj_px = 2.0;  // threshold a + b d (px) on the offset of the current position
  double b_reproj = 0.05;
  double a_disp_px = 1.0;  // and on the disparity residual
  double b_disp = 0.05;
  double adaptive_k = 3.0;  // a = clamp(k * robust sigma, a_*, max_scale * a_*)
  double max_scale = 2.5;
  // The motion between reference and current frame is the chain of the per-frame depth test's motions (each from
  // PnP RANSAC): the tracks within ransac_reprojection_px of where it puts them are the PnP inliers when they are
  // >= this fraction of the tracks used, and the least-squares refinement starts from it; fewer (the chain drifted
  // or broke): PnP RANSAC as before. 0 = always RANSAC.
  double prior_min_inlier_fraction = 0.5;
  int verify_levels = 1;             // LK pyramid levels of the verification (reach ~4 x window / 2 px)
  double verify_fb_px = 1.0;         // its forward-backward check
  double verify_max_shift_px = 1.0;  // the track's reference position is confirmed within this
  // Depth-edge check (done by the detector, which has the stereo matcher): a confirmed track whose disparity
  // differs from the disparity edge_check_px left, right, above or below it by more than edge_tolerance_px +
  // edge_tolerance_rel * d straddles a depth edge (its LK window mixes two surfaces that move apart over the
  // frames): not dynamic by this test. 0 = off.
  int edge_check_px = 6;
  double edge_tolerance_px = 1.0;
  double edge_tolerance_rel = 0.1;
  // Stereo check (also by the detector): a static point whose disparity is consistently wrong (the matcher locked
  // onto the wrong period of repetitive racking) moves over the longer baseline exactly like an object keeping its
  // distance. A confirmed track's disparity is measured again with a (2 h + 1)^2 window, h = check_half_window,
  // and a uniqueness margin of check_uniqueness_margin; a differing (by > edge_tolerance_px + rel * d) or missing
  // match makes it not dynamic by this test. 0 = off.
  int check_half_window = 8;
  double check_uniqueness_margin = 0.2;
  // Aperture check: a track on an edge-like patch (least / largest eigenvalue of its gradient structure tensor
  // below aperture_ratio) slides along the edge over the frames, and the verification cannot tell (LK into the
  // reference does not move along the edge either). For such a track only the part of the offset across the
  // edge (along the strong gradient) counts for the 2-D test. 0 = off.
  double aperture_ratio = 0.15;
  // What makes a frame-to-frame step of a track "consistent" (TrackHistory: only tracks whose every step since the
  // reference was consistent are tested). false: the per-frame depth test passed the track (a mover the per-frame
  // test flagged even once is never tested here). true: its disparity changed as the ego-motion predicts (the
  // per-frame disparity residual within its threshold): a stereo mismatch in one frame still breaks the chain, but
  // a person 7 m away whose per-frame offset hovers around the per-frame threshold keeps a history to test.
  bool chain_stereo_only = true;
  double chain_stereo_factor = 4.0;  // ... but such a track is dynamic only when off by this many times the thresholds

  void validate(const std::string& source) const;
  std::string describe() const;
};

// The last observations of the detector's tracks. Track i of the current list has observations in this and
// up to depth-1 earlier frames (fewer when it is younger).
class TrackHistory {
 public:
  static constexpr uint8_t kStepBroken = 0, kStepConsistent = 1, kStepStereoOnly = 2;
  explicit TrackHistory(int depth = 13);
  int depth() const { return depth_; }
  std::size_t size() const { return age_.size(); }
  void clear();

  // Moves to the next frame: every track continues, observed at px[i] with disparity d[i] (0 = none);
  // consistent[i]: how this observation agrees with the previous one under the frame's ego-motion (kStepConsistent:
  // the per-frame depth test measured both residuals and passed the track; kStepStereoOnly: the test flagged it,
  // but its disparity changed as the ego-motion predicts; kStepBroken: neither, or not measured).
  void next_frame(const std::vector<cv::Point2f>& px, const std::vector<float>& d,
                  const std::vector<uint8_t>& consistent);
  // Ends the tracks with keep[i] == 0 (the others keep their order).
  void retain(const std::vector<uint8_t>& keep);
  // Appends a track observed in the current frame.
  void add(const cv::Point2f& px, float d);
  // Gives the last added track an observation `back` (1 .. depth-1) frames before the current one.
  void add_earlier(int back, const cv::Point2f& px, float d);

  // Observation of track i `back` frames before the current frame (0 = current); false when it did not exist.
  bool observation(std::size_t i, int back, cv::Point2f& px, float& d) const;
  int age(std::size_t i) const { return age_[i]; }  // frames observed before the current one
  // Number of most recent frame-to-frame steps of track i that were consistent: its observations `back` frames
  // ago and since agree with each other when consistent_steps(i) >= back (a stereo mismatch in one frame breaks it).
  int consistent_steps(std::size_t i) const { return run_[i]; }
  // consistent_steps() counts the steps marked kStepConsistent or kStepStereoOnly; this one only kStepConsistent.
  int consistent_steps_strict(std::size_t i) const { return strict_run_[i]; }

 private:
  int depth_;
  int64_t frame_ = 0;  // current frame number (slot = frame % depth)
  std::vector<int> age_, run_, strict_run_;
  std::vector<cv::Point2f> px_;  // size() x depth, slot-major per track
  std::vector<float> d_;
};

struct MultiFrameResult {
  bool valid = false;        // a reference was available and the motion to it was estimated
  int frames_back = 0;       // the reference is this many frames before the current one
  double translation_m = 0;  // camera translation between the two (chained estimate)
  double rotation_deg = 0;
  int candidates = 0;                 // tracks observed in both frames with a usable disparity
  int flagged = 0, confirmed = 0;     // tracks the test flagged, and of those the ones the verification kept
  SE3d T_cur_ref = SE3d::Identity();  // estimated motion (reference camera -> current camera)
  cv::Mat reference_left;             // the reference frame's left image (shared; valid until the next run)
  DepthTestResult test;               // per track (current list) residuals and decisions
};

// Aperture check of one track: for an edge-like (2 half + 1)^2 patch of `image` (CV_8UC1) around p (least / largest
// eigenvalue of its gradient structure tensor below ratio), the component along the strong gradient of the offset
// between the prediction (ref_px with ref_disparity_px moved by T_cur_ref and projected) and p; -1 for a
// well-conditioned patch (the whole offset counts), a patch without gradient or one too close to the border.
double offset_across_edge(const cv::Mat& image, const cv::Point2f& p, int half, const PinholeCamera& camera,
                          double bf_px_m, const SE3d& T_cur_ref, const cv::Point2f& ref_px, float ref_disparity_px,
                          double ratio);

class MultiFrameTest {
 public:
  explicit MultiFrameTest(const MultiFrameTestConfig& config = {});
  const MultiFrameTestConfig& config() const { return config_; }

  // Forgets the chain of motions.
  void reset();
  // Extends the chain with this frame: its ego-motion (previous camera -> current camera; an invalid one breaks
  // the chain: earlier frames cannot be related to later ones) and its left image (copied).
  void add_frame(const SE3d& T_cur_prev, bool valid, const cv::Mat& left);

  // Tests each track of `history` (current observation at index 0) with usable[i] against its observation in
  // the reference frame. Sizes: history.size() == usable.size(). cur_pyramid: the current left image's LK
  // pyramid (at least verify_levels levels) built with tracking's window, whose criteria the verification uses.
  void run(const PinholeCamera& camera, double bf_px_m, const TrackHistory& history, const std::vector<uint8_t>& usable,
           const std::vector<cv::Mat>& cur_pyramid, const LkTrackerConfig& tracking, MultiFrameResult& result);

  int chain_length() const { return static_cast<int>(frames_.size()); }

 private:
  // Steps of track i held since the reference (multiframe.chain_stereo_only: stereo agreement counts).
  int held_steps(const TrackHistory& history, std::size_t i) const;
  // The reference frame (frames back; -1: none) and the motion from the current camera to it.
  int choose_reference(const TrackHistory& history, const std::vector<uint8_t>& usable, SE3d& T_ref_cur) const;
  // The flagged tracks verified by LK into the reference image.
  void verify_flagged(const PinholeCamera& camera, double bf_px_m, const TrackHistory& history,
                      const std::vector<cv::Mat>& cur_pyramid, const LkTrackerConfig& tracking, int chosen,
                      MultiFrameResult& result);
  // ... and track i's verdict, found at `found` in the reference image.
  void judge_verified(const PinholeCamera& camera, double bf_px_m, const TrackHistory& history, const cv::Mat& cur_left,
                      int half_window_px, int chosen, std::size_t i, const cv::Point2f& found,
                      MultiFrameResult& result) const;

  MultiFrameTestConfig config_;
  DepthConsistencyTest test_;
  struct Frame {
    SE3d T_w_c;
    cv::Mat left;
  };
  std::deque<Frame> frames_;    // the chained frames, the current one last
  std::vector<cv::Mat> spare_;  // image buffers of dropped frames, reused
  std::vector<cv::Mat> ref_pyramid_;
  std::vector<cv::Point2f> cand_cur_, cand_ref_, cand_back_;
  std::vector<int> cand_index_;
  std::vector<uint8_t> status_, back_status_;
  std::vector<float> errors_;
  std::vector<cv::Point2f> ref_px_, cur_px_;
  std::vector<float> ref_d_, cur_d_;
  std::vector<uint8_t> both_;
};

}  // namespace agvslam::dynamic
