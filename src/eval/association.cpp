#include "agvslam/eval/association.h"

#include <algorithm>
#include <cstdlib>
#include <numeric>

namespace agvslam::eval {

PosePairs associate_by_index(const Trajectory& gt, const Trajectory& est) {
  PosePairs pairs;
  const std::size_t n = std::min(gt.size(), est.size());
  for (std::size_t i = 0; i < n; ++i) {
    pairs.t_ns.push_back(est[i].t_ns);
    pairs.T_w_c_gt.push_back(gt[i].T_w_c);
    pairs.T_w_c_est.push_back(est[i].T_w_c);
  }
  return pairs;
}

PosePairs associate_by_timestamp(const Trajectory& gt, const Trajectory& est, int64_t max_dt_ns) {
  std::vector<std::size_t> gt_order(gt.size());
  std::iota(gt_order.begin(), gt_order.end(), 0);
  std::sort(gt_order.begin(), gt_order.end(), [&](std::size_t a, std::size_t b) { return gt[a].t_ns < gt[b].t_ns; });
  std::vector<std::size_t> est_order(est.size());
  std::iota(est_order.begin(), est_order.end(), 0);
  std::sort(est_order.begin(), est_order.end(),
            [&](std::size_t a, std::size_t b) { return est[a].t_ns < est[b].t_ns; });

  std::vector<bool> gt_used(gt.size(), false);
  PosePairs pairs;
  for (const std::size_t ei : est_order) {
    const int64_t t = est[ei].t_ns;
    auto it = std::lower_bound(gt_order.begin(), gt_order.end(), t,
                               [&](std::size_t gi, int64_t value) { return gt[gi].t_ns < value; });
    std::size_t best = gt.size();
    int64_t best_dt = max_dt_ns + 1;
    for (auto cand = (it == gt_order.begin() ? it : it - 1); cand != gt_order.end() && cand <= it; ++cand) {
      const int64_t dt = std::llabs(gt[*cand].t_ns - t);
      if (!gt_used[*cand] && dt < best_dt) {
        best_dt = dt;
        best = *cand;
      }
    }
    if (best == gt.size()) continue;
    gt_used[best] = true;
    pairs.t_ns.push_back(t);
    pairs.T_w_c_gt.push_back(gt[best].T_w_c);
    pairs.T_w_c_est.push_back(est[ei].T_w_c);
  }
  return pairs;
}

}  // namespace agvslam::eval
