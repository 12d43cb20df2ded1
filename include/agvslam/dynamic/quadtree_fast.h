#pragma once
// Quadtree-distributed FAST corners (paper 004, III.A, Fig. 2b):
//   (1) the image is divided into square cells and FAST extracts an excess of corners in each cell (cells
//       where nothing passes the normal threshold fall back to a lower one);
//   (2) initial nodes cover the image and hold the corners;
//   (3) a node holding more than one corner is split into four;
//   (4) (3) repeats until N nodes hold a corner; the strongest corner of each node is kept.
// The result is exactly N corners when at least N candidates exist (the last round can overshoot by up
// to three nodes; the weakest of those node winners are dropped).

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::dynamic {

// params/dynamic.yaml, section `features`.
struct QuadtreeFastConfig {
  int target_count = 300;  // N: corners returned (when available)
  int cell_size_px = 32;   // side of the extraction cells
  int threshold = 20;      // FAST threshold (grey levels)
  int min_threshold = 7;   // fallback threshold in cells with no corner at `threshold`
  int border_px = 16;      // no corner closer than this to the image edge (LK and stereo windows fit)

  void validate(const std::string& source) const;
  std::string describe() const;
};

struct Corner {
  cv::Point2f pt;
  float response = 0;  // FAST score
};

struct QuadtreeStats {
  int candidates = 0;                  // corners after the per-cell threshold choice
  int weak_cells = 0;                  // cells that used min_threshold
  std::vector<cv::Rect2f> node_rects;  // the final nodes (filled only when collect_nodes is true)
};

// Step (2)-(4) on given candidates inside `area`: one corner per node, the strongest; exactly
// min(target_count, distinct nodes) corners, sorted by decreasing response. node_rects (optional) receives
// the rectangle of the node each returned corner comes from (same order).
std::vector<Corner> distribute_quadtree(const std::vector<Corner>& candidates, const cv::Rect2f& area, int target_count,
                                        std::vector<cv::Rect2f>* node_rects = nullptr);

class QuadtreeFast {
 public:
  explicit QuadtreeFast(const QuadtreeFastConfig& config = {});
  const QuadtreeFastConfig& config() const { return config_; }

  // grey: CV_8UC1. Replaces `corners`.
  void detect(const cv::Mat& grey, std::vector<Corner>& corners, QuadtreeStats* stats = nullptr,
              bool collect_nodes = false);

  // How step (1) finds the candidates; both give the same corners in the same order. kSinglePass: FAST once at
  // min_threshold everywhere, then the weak corners of cells that hold a strong one are dropped. kTwoPass: FAST at
  // `threshold` everywhere, then at min_threshold only in the runs of cells without a strong corner (FAST at 20 is
  // ~3x cheaper than at 7 on textured images). kAuto: two passes when fewer than 40 % of the previous image's cells
  // were weak (a textured warehouse: ~15 %), one pass otherwise (EuRoC's plain walls: ~65 %).
  enum class Extraction { kAuto, kSinglePass, kTwoPass };
  void set_extraction(Extraction e) { extraction_ = e; }

 private:
  // Candidates of step (1) in `area` (image coordinates) into candidates_, FAST's order (row by row), and each
  // cell's best response into cell_best_ (cells_x_ x cells_y_ cells, -1 = none).
  void single_pass(const cv::Mat& grey, const cv::Rect& area, const cv::Rect& with_ring);
  void two_pass(const cv::Mat& grey, const cv::Rect& area, const cv::Rect& with_ring);
  // FAST at `threshold` on grey(rect); the corners inside `keep` join candidates_ and their cells' best responses.
  void fast_into_candidates(const cv::Mat& grey, const cv::Rect& rect, int threshold, const cv::Rect& keep,
                            const cv::Rect& area);
  std::size_t cell_of(const cv::Point2f& p, const cv::Rect& area) const;  // index of the cell holding p

  QuadtreeFastConfig config_;
  Extraction extraction_ = Extraction::kAuto;
  double last_weak_fraction_ = -1;  // of the previous image's cells (-1: none yet)
  std::vector<cv::KeyPoint> keypoints_;
  std::vector<Corner> candidates_;
  std::vector<float> cell_best_;
  int cells_x_ = 0, cells_y_ = 0;  // the cell grid of the current image's area
};

}  // namespace agvslam::dynamic
