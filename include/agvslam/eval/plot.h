#pragma once
// Top view of a ground-truth and an estimated trajectory, as an image a person looks at: the plane is the one
// in which the ground truth spreads most (for a ground vehicle, the floor), with labelled axes in metres, a
// grid, a scale bar, a legend and a title.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

namespace agvslam::eval {

struct PlotOptions {
  int width_px = 1000;
  int height_px = 800;
  std::string title;
  std::string gt_label = "ground truth";
  std::string est_label = "estimate (aligned)";
};

// Returns a CV_8UC3 image. Either list may be empty (not both).
cv::Mat plot_top_view(const std::vector<Eigen::Vector3d>& p_gt, const std::vector<Eigen::Vector3d>& p_est,
                      const PlotOptions& options);
// Writes the plot; throws InputError naming the path when it cannot be written.
void save_top_view(const std::string& path, const std::vector<Eigen::Vector3d>& p_gt,
                   const std::vector<Eigen::Vector3d>& p_est, const PlotOptions& options);

}  // namespace agvslam::eval
