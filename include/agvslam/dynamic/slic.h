#pragma once
// SLIC superpixels on a grey image (paper 004, III.B, eqs. 5-7), in two variants that share everything but
// the assignment step:
//   plain        each iteration, every cluster centre evaluates D_SLIC (eq. 5) on all pixels of its
//                2S x 2S window and the nearest centre wins (Achanta et al.);
//   incremental  (the paper's variant) only "unstable" pixels are evaluated. The first round is a full
//                assignment (before it no pixel has a cluster); then the edge pixels of the clustering are
//                unstable and, after each assignment, per eq. 7, a 4-neighbour p
//                of an evaluated pixel q becomes unstable when cluster(p) != cluster(q) or q is still
//                unstable (its cluster changed); everything else becomes stable. An unstable pixel is
//                compared with every centre whose 2S x 2S window contains it, as in the plain variant (found
//                among the 3 x 3 seeds around its grid cell: centres stay near their seeds). Cluster centres are kept
//                as running sums, updated only for the pixels that changed.
// Both stop after `iterations` rounds or when a round changes fewer than min_change_fraction of the pixels
// (0: only when no label changes); both end with the connectivity
// step (4-connected components, fragments smaller than min_segment_fraction * S^2 merged into a neighbour).
// D_SLIC = sqrt((dg / N_c)^2 + (ds / N_s)^2) with N_s = S = sqrt(m n / K) (eq. 6); the square root is
// monotonic and not taken.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::dynamic {

// params/dynamic.yaml, section `slic`.
struct SlicConfig {
  int superpixel_size_px = 12;       // S (eq. 6): K = m n / S^2 seeds
  int max_superpixels = 800;         // per ROI; S grows when a large ROI would need more
  double max_color_distance = 16.0;  // N_c (grey levels): lower = superpixels follow intensity edges more
  int iterations = 10;
  double min_change_fraction = 0.02;  // converged when a round changes fewer than this fraction of the pixels
  bool incremental = false;           // the paper's unstable-pixel update (false = plain SLIC, faster here)
  double min_segment_fraction = 0.25;

  void validate(const std::string& source) const;
  std::string describe() const;
};

// Work counters. distance_evaluations alone flatters the incremental variant: it also spends work finding each
// unstable pixel's candidate centres and keeping the unstable set. candidate_checks counts every (pixel, centre)
// pair considered (a rejected window test too; in the plain variant every one is evaluated), pixel_visits every
// pixel touched by the bookkeeping (buffer resets, change counts, centre sums, the unstable set); work() is their
// sum, one unit each (it tracks callgrind instruction counts: see tests/bench/bench_dynamic.cpp BM_DynamicSlic).
struct SlicStats {
  int64_t distance_evaluations = 0;  // D_SLIC computations in total
  int64_t candidate_checks = 0;
  int64_t pixel_visits = 0;
  int64_t work() const { return candidate_checks + pixel_visits; }
  std::vector<int64_t> evaluations_per_iteration;
  std::vector<int> changed_per_iteration;  // pixels whose cluster changed
  int iterations = 0;
  int step_px = 0;      // S actually used
  int seeds = 0;        // K
  int superpixels = 0;  // after the connectivity step
};

class Slic {
 public:
  explicit Slic(const SlicConfig& config = {});
  const SlicConfig& config() const { return config_; }

  // grey: CV_8UC1 (typically a ROI crop). labels: CV_32SC1 of the same size, 0 .. count-1, each label one
  // 4-connected region. Returns the number of superpixels. Uses config().incremental.
  int segment(const cv::Mat& grey, cv::Mat& labels, SlicStats* stats = nullptr);
  // Same with the variant chosen explicitly.
  int segment(const cv::Mat& grey, cv::Mat& labels, bool incremental, SlicStats* stats);

 private:
  struct Centre {
    float g = 0, x = 0, y = 0;
  };
  struct Window {
    int x0, x1, y0, y1;
  };
  struct Sums {
    double g = 0, x = 0, y = 0;
    int64_t n = 0;
  };
  // The seed grid of one image and the buffers the steps share.
  struct Grid {
    int W = 0, H = 0;
    std::size_t P = 0;          // pixels
    int nx = 0, ny = 0, K = 0;  // seeds per row / column, in all
    double sx = 0, sy = 0;      // grid cell size (px)
    double step = 0;            // N_s = S_step (px)
    int win = 0;                // a centre's search window: +- win px around it
    float inv_nc2 = 0, inv_ns2 = 0;
    const uint8_t* img = nullptr;
    int32_t* lab = nullptr;  // the labels being computed
    cv::Mat grey_copy;       // the image when it is not continuous
  };
  struct Counters {
    int64_t candidates = 0, visits = 0;  // SlicStats::candidate_checks, pixel_visits
  };
  Grid make_grid(const cv::Mat& grey, cv::Mat& labels) const;
  // Grid labels, the seed centres (3x3 mean grey) and the clusters' running sums.
  void seed(const Grid& g);
  void accumulate_sums(const Grid& g);
  // Step (2), every pixel against the centres whose window holds it; returns the distances evaluated.
  int64_t assign_all(const Grid& g, Counters& counters);
  // Step (2), the unstable pixels only (incremental).
  int64_t assign_unstable(const Grid& g, Counters& counters);
  void find_cell_candidates(const Grid& g);
  // Step (3): the centres from the clusters; returns the pixels whose cluster changed this round.
  int update_centres(const Grid& g, bool full, Counters& counters);
  // Incremental: after the first round the clusters' edge pixels are unstable; then eq. 7 passes it on.
  void mark_edges_unstable(const Grid& g, Counters& counters);
  void propagate_unstable(const Grid& g, Counters& counters);
  int enforce_connectivity(cv::Mat& labels, int min_size);

  SlicConfig config_;
  std::vector<Centre> centres_;
  std::vector<Sums> sums_;
  std::vector<float> dist_;
  std::vector<int32_t> old_label_;
  std::vector<uint8_t> flag_;
  std::vector<int32_t> unstable_, next_unstable_;
  std::vector<int32_t> relabel_, queue_;
  std::vector<Window> window_;
  std::vector<int32_t> cell_candidates_;  // incremental: per grid cell, up to 9 centres whose window overlaps it
  std::vector<int> cell_count_;
  std::vector<int> cell_x_, cell_y_;  // per column / row: its grid cell
};

}  // namespace agvslam::dynamic
