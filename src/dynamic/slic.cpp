#include "agvslam/dynamic/slic.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>

namespace agvslam::dynamic {

Slic::Slic(const SlicConfig& config) : config_(config) { config_.validate("SlicConfig"); }

int Slic::segment(const cv::Mat& grey, cv::Mat& labels, SlicStats* stats) {
  return segment(grey, labels, config_.incremental, stats);
}

Slic::Grid Slic::make_grid(const cv::Mat& grey, cv::Mat& labels) const {
  Grid g;
  g.W = grey.cols;
  g.H = grey.rows;
  g.P = static_cast<std::size_t>(g.W) * static_cast<std::size_t>(g.H);
  // Seeds on a regular grid (eq. 6), at most max_superpixels of them.
  double S = config_.superpixel_size_px;
  if (static_cast<double>(g.P) / (S * S) > config_.max_superpixels) {
    S = std::sqrt(static_cast<double>(g.P) / config_.max_superpixels);
  }
  g.nx = std::max(1, static_cast<int>(std::lround(g.W / S)));
  g.ny = std::max(1, static_cast<int>(std::lround(g.H / S)));
  g.K = g.nx * g.ny;
  g.sx = static_cast<double>(g.W) / g.nx;
  g.sy = static_cast<double>(g.H) / g.ny;
  g.step = std::sqrt(static_cast<double>(g.P) / g.K);  // N_s = S_step
  g.win = std::max(1, static_cast<int>(std::lround(g.step)));
  g.inv_nc2 = static_cast<float>(1.0 / (config_.max_color_distance * config_.max_color_distance));
  g.inv_ns2 = static_cast<float>(1.0 / (g.step * g.step));
  labels.create(g.H, g.W, CV_32SC1);
  CV_Assert(labels.isContinuous());
  g.lab = labels.ptr<int32_t>();
  if (!grey.isContinuous()) g.grey_copy = grey.clone();
  g.img = grey.isContinuous() ? grey.ptr<uint8_t>() : g.grey_copy.ptr<uint8_t>();
  return g;
}

void Slic::accumulate_sums(const Grid& g) {
  sums_.assign(static_cast<std::size_t>(g.K), Sums{});
  for (int y = 0; y < g.H; ++y) {
    for (int x = 0; x < g.W; ++x) {
      Sums& s = sums_[static_cast<std::size_t>(g.lab[y * g.W + x])];
      s.g += g.img[y * g.W + x];
      s.x += x;
      s.y += y;
      ++s.n;
    }
  }
}

void Slic::seed(const Grid& g) {
  // Grid labels, seed centres (3x3 mean grey) and running sums.
  cell_x_.resize(static_cast<std::size_t>(g.W));
  cell_y_.resize(static_cast<std::size_t>(g.H));
  for (int x = 0; x < g.W; ++x) cell_x_[static_cast<std::size_t>(x)] = std::min(g.nx - 1, static_cast<int>(x / g.sx));
  for (int y = 0; y < g.H; ++y) cell_y_[static_cast<std::size_t>(y)] = std::min(g.ny - 1, static_cast<int>(y / g.sy));
  for (int y = 0; y < g.H; ++y) {
    for (int x = 0; x < g.W; ++x) {
      g.lab[y * g.W + x] = cell_y_[static_cast<std::size_t>(y)] * g.nx + cell_x_[static_cast<std::size_t>(x)];
    }
  }
  centres_.resize(static_cast<std::size_t>(g.K));
  for (int j = 0; j < g.ny; ++j) {
    for (int i = 0; i < g.nx; ++i) {
      Centre& c = centres_[static_cast<std::size_t>(j * g.nx + i)];
      c.x = static_cast<float>((i + 0.5) * g.sx - 0.5);
      c.y = static_cast<float>((j + 0.5) * g.sy - 0.5);
      const int cx = std::clamp(static_cast<int>(std::lround(c.x)), 0, g.W - 1);
      const int cy = std::clamp(static_cast<int>(std::lround(c.y)), 0, g.H - 1);
      int sum = 0, n = 0;
      for (int v = std::max(0, cy - 1); v <= std::min(g.H - 1, cy + 1); ++v) {
        for (int u = std::max(0, cx - 1); u <= std::min(g.W - 1, cx + 1); ++u) {
          sum += g.img[v * g.W + u];
          ++n;
        }
      }
      c.g = static_cast<float>(sum) / static_cast<float>(n);
    }
  }
  accumulate_sums(g);
}

int64_t Slic::assign_all(const Grid& g, Counters& counters) {
  std::fill(dist_.begin(), dist_.end(), std::numeric_limits<float>::infinity());
  std::memcpy(old_label_.data(), g.lab, g.P * sizeof(int32_t));
  counters.visits += 2 * static_cast<int64_t>(g.P);  // the distance and label buffers
  int64_t evals = 0;
  for (int k = 0; k < g.K; ++k) {
    const Centre& c = centres_[static_cast<std::size_t>(k)];
    const int x0 = std::max(0, static_cast<int>(std::floor(c.x)) - g.win);
    const int x1 = std::min(g.W - 1, static_cast<int>(std::ceil(c.x)) + g.win);
    const int y0 = std::max(0, static_cast<int>(std::floor(c.y)) - g.win);
    const int y1 = std::min(g.H - 1, static_cast<int>(std::ceil(c.y)) + g.win);
    for (int y = y0; y <= y1; ++y) {
      const float dy = static_cast<float>(y) - c.y;
      const float dy2 = dy * dy * g.inv_ns2;
      const uint8_t* g_row = g.img + y * g.W;
      float* d_row = dist_.data() + y * g.W;
      int32_t* l_row = g.lab + y * g.W;
      for (int x = x0; x <= x1; ++x) {  // branch-free so that it vectorises
        const float dg = static_cast<float>(g_row[x]) - c.g;
        const float dx = static_cast<float>(x) - c.x;
        const float D = dg * dg * g.inv_nc2 + dx * dx * g.inv_ns2 + dy2;  // eq. 5, squared
        const float old = d_row[x];
        const int32_t take = -static_cast<int32_t>(D < old);  // all ones when this centre is nearer
        d_row[x] = std::min(D, old);
        l_row[x] = (l_row[x] & ~take) | (k & take);
      }
      evals += x1 - x0 + 1;
    }
  }
  counters.candidates += evals;  // every pixel of every window is evaluated
  return evals;
}

void Slic::find_cell_candidates(const Grid& g) {
  window_.resize(static_cast<std::size_t>(g.K));
  for (int k = 0; k < g.K; ++k) {
    const Centre& c = centres_[static_cast<std::size_t>(k)];
    window_[static_cast<std::size_t>(k)] = {
        static_cast<int>(std::floor(c.x)) - g.win, static_cast<int>(std::ceil(c.x)) + g.win,
        static_cast<int>(std::floor(c.y)) - g.win, static_cast<int>(std::ceil(c.y)) + g.win};
  }
  cell_candidates_.resize(static_cast<std::size_t>(g.K) * 9);
  cell_count_.assign(static_cast<std::size_t>(g.K), 0);
  for (int cj = 0; cj < g.ny; ++cj) {
    const int cy0 = static_cast<int>(std::ceil(cj * g.sy - 0.5)),
              cy1 = static_cast<int>(std::floor((cj + 1) * g.sy - 0.5));
    for (int ci = 0; ci < g.nx; ++ci) {
      const int cx0 = static_cast<int>(std::ceil(ci * g.sx - 0.5)),
                cx1 = static_cast<int>(std::floor((ci + 1) * g.sx - 0.5));
      const int cell = cj * g.nx + ci;
      int n_cell = 0;
      for (int j = std::max(0, cj - 1); j <= std::min(g.ny - 1, cj + 1); ++j) {
        for (int i = std::max(0, ci - 1); i <= std::min(g.nx - 1, ci + 1); ++i) {
          const Window& w = window_[static_cast<std::size_t>(j * g.nx + i)];
          if (w.x1 < cx0 || w.x0 > cx1 || w.y1 < cy0 || w.y0 > cy1) continue;
          cell_candidates_[static_cast<std::size_t>(cell) * 9 + static_cast<std::size_t>(n_cell++)] = j * g.nx + i;
        }
      }
      cell_count_[static_cast<std::size_t>(cell)] = n_cell;
    }
  }
}

int64_t Slic::assign_unstable(const Grid& g, Counters& counters) {
  // Only the unstable pixels, each against the centres whose 2S x 2S window contains it (as in the plain variant).
  // Centres stay within about half a grid cell of their seed, so those are among the 3 x 3 seeds around the pixel's
  // grid cell: per grid cell, the centres whose window overlaps it (usually 4), 9 window tests instead of a search.
  find_cell_candidates(g);
  counters.candidates += 9 * static_cast<int64_t>(g.K);
  for (int32_t q : unstable_) old_label_[static_cast<std::size_t>(q)] = g.lab[q];
  counters.visits += static_cast<int64_t>(unstable_.size());  // the label copy
  int64_t evals = 0;
  for (int32_t q : unstable_) {
    const int y = q / g.W;
    const int x = q - y * g.W;
    const float grey = static_cast<float>(g.img[q]);
    const int cell = cell_y_[static_cast<std::size_t>(y)] * g.nx + cell_x_[static_cast<std::size_t>(x)];
    const int32_t* cand = cell_candidates_.data() + static_cast<std::size_t>(cell) * 9;
    const int n_cand = cell_count_[static_cast<std::size_t>(cell)];
    counters.candidates += n_cand;
    float best = std::numeric_limits<float>::infinity();
    int32_t best_k = g.lab[q];
    for (int c = 0; c < n_cand; ++c) {
      const int k = cand[c];
      const Window& w = window_[static_cast<std::size_t>(k)];
      if (x < w.x0 || x > w.x1 || y < w.y0 || y > w.y1) continue;
      ++evals;
      const Centre& ce = centres_[static_cast<std::size_t>(k)];
      const float dg = grey - ce.g;
      const float dx = static_cast<float>(x) - ce.x, dy = static_cast<float>(y) - ce.y;
      const float D = dg * dg * g.inv_nc2 + (dx * dx + dy * dy) * g.inv_ns2;  // eq. 5, squared
      if (D < best || (D == best && k < best_k)) {
        best = D;
        best_k = k;
      }
    }
    g.lab[q] = best_k;
  }
  return evals;
}

int Slic::update_centres(const Grid& g, bool full, Counters& counters) {
  int changed = 0;
  if (full) {
    for (std::size_t p = 0; p < g.P; ++p) changed += g.lab[p] != old_label_[p];
    counters.visits += 2 * static_cast<int64_t>(g.P);  // the change count and the sums
    accumulate_sums(g);
  } else {
    counters.visits += static_cast<int64_t>(unstable_.size());
    for (int32_t q : unstable_) {
      const int32_t now = g.lab[q], before = old_label_[static_cast<std::size_t>(q)];
      if (now == before) continue;
      ++changed;
      const int x = q % g.W, y = q / g.W;
      Sums& a = sums_[static_cast<std::size_t>(before)];
      Sums& b = sums_[static_cast<std::size_t>(now)];
      a.g -= g.img[q];
      a.x -= x;
      a.y -= y;
      --a.n;
      b.g += g.img[q];
      b.x += x;
      b.y += y;
      ++b.n;
    }
  }
  for (int k = 0; k < g.K; ++k) {
    const Sums& s = sums_[static_cast<std::size_t>(k)];
    if (s.n <= 0) continue;
    Centre& c = centres_[static_cast<std::size_t>(k)];
    const double inv = 1.0 / static_cast<double>(s.n);
    c.g = static_cast<float>(s.g * inv);
    c.x = static_cast<float>(s.x * inv);
    c.y = static_cast<float>(s.y * inv);
  }
  return changed;
}

void Slic::mark_edges_unstable(const Grid& g, Counters& counters) {
  // Step (1): the edge pixels of the clustering are unstable.
  unstable_.clear();
  counters.visits += static_cast<int64_t>(g.P);
  for (int y = 0; y < g.H; ++y) {
    for (int x = 0; x < g.W; ++x) {
      const int32_t* lab = g.lab;
      const int W = g.W;
      const int32_t l = lab[y * W + x];
      const bool edge = (x > 0 && lab[y * W + x - 1] != l) || (x + 1 < W && lab[y * W + x + 1] != l) ||
                        (y > 0 && lab[(y - 1) * W + x] != l) || (y + 1 < g.H && lab[(y + 1) * W + x] != l);
      if (edge) {
        flag_[static_cast<std::size_t>(y * W + x)] = 1;
        unstable_.push_back(y * W + x);
      }
    }
  }
}

void Slic::propagate_unstable(const Grid& g, Counters& counters) {
  // Eq. 7: p (4-neighbour of an evaluated q) is unstable next round when cluster(p) != cluster(q) or q is still
  // unstable (its cluster changed this round). Bit 1 of flag_ marks the next round's set.
  next_unstable_.clear();
  auto mark = [&](int32_t p) {
    uint8_t& f = flag_[static_cast<std::size_t>(p)];
    if (f & 2) return;
    f |= 2;
    next_unstable_.push_back(p);
  };
  const int32_t* lab = g.lab;
  const int W = g.W;
  for (int32_t q : unstable_) {
    const int32_t lq = lab[q];
    const bool still_unstable = lq != old_label_[static_cast<std::size_t>(q)];
    const int y = q / W;
    const int x = q - y * W;
    if (still_unstable) mark(q);
    if (x > 0 && (still_unstable || lab[q - 1] != lq)) mark(q - 1);
    if (x + 1 < W && (still_unstable || lab[q + 1] != lq)) mark(q + 1);
    if (y > 0 && (still_unstable || lab[q - W] != lq)) mark(q - W);
    if (y + 1 < g.H && (still_unstable || lab[q + W] != lq)) mark(q + W);
  }
  for (int32_t q : unstable_) flag_[static_cast<std::size_t>(q)] &= static_cast<uint8_t>(~1u);
  for (int32_t p : next_unstable_) flag_[static_cast<std::size_t>(p)] = 1;
  counters.visits += 2 * static_cast<int64_t>(unstable_.size()) + static_cast<int64_t>(next_unstable_.size());
  unstable_.swap(next_unstable_);
}

int Slic::segment(const cv::Mat& grey, cv::Mat& labels, bool incremental, SlicStats* stats) {
  CV_Assert(grey.type() == CV_8UC1);
  if (stats) *stats = SlicStats{};
  if (grey.cols == 0 || grey.rows == 0) {
    labels.release();
    return 0;
  }
  const Grid g = make_grid(grey, labels);
  seed(g);
  dist_.resize(g.P);
  old_label_.resize(g.P);
  flag_.assign(g.P, 0);
  unstable_.clear();
  Counters counters;
  int64_t total_evals = 0;
  int iterations_run = 0;
  for (int it = 0; it < config_.iterations; ++it) {
    // The first round is a full assignment in both variants (before it no pixel has a cluster, so "edge
    // pixels" are not defined); the incremental variant then revisits only unstable pixels.
    const bool full = !incremental || it == 0;
    if (!full && unstable_.empty()) break;
    // Step (2): assignment; step (3): cluster centres.
    const int64_t evals = full ? assign_all(g, counters) : assign_unstable(g, counters);
    const int changed = update_centres(g, full, counters);
    total_evals += evals;
    iterations_run = it + 1;
    if (stats) {
      stats->evaluations_per_iteration.push_back(evals);
      stats->changed_per_iteration.push_back(changed);
    }
    if (changed == 0 || changed < config_.min_change_fraction * static_cast<double>(g.P)) break;
    if (incremental && it == 0) {
      mark_edges_unstable(g, counters);
    } else if (incremental) {
      propagate_unstable(g, counters);
    }
  }

  const int min_size = static_cast<int>(config_.min_segment_fraction * g.step * g.step);
  const int count = enforce_connectivity(labels, min_size);
  if (stats) {
    stats->distance_evaluations = total_evals;
    stats->candidate_checks = counters.candidates;
    stats->pixel_visits = counters.visits;
    stats->iterations = iterations_run;
    stats->step_px = static_cast<int>(std::lround(g.step));
    stats->seeds = g.K;
    stats->superpixels = count;
  }
  return count;
}

int Slic::enforce_connectivity(cv::Mat& labels, int min_size) {
  const int W = labels.cols, H = labels.rows;
  const std::size_t P = static_cast<std::size_t>(W) * static_cast<std::size_t>(H);
  int32_t* lab = labels.ptr<int32_t>();
  relabel_.assign(P, -1);
  queue_.clear();
  int next_label = 0;
  for (int start = 0; start < static_cast<int>(P); ++start) {
    if (relabel_[static_cast<std::size_t>(start)] >= 0) continue;
    const int32_t old = lab[start];
    const int sx = start % W, sy = start / W;
    int32_t adjacent = -1;
    if (sx > 0) adjacent = relabel_[static_cast<std::size_t>(start - 1)];
    if (adjacent < 0 && sy > 0) adjacent = relabel_[static_cast<std::size_t>(start - W)];
    queue_.clear();
    queue_.push_back(start);
    relabel_[static_cast<std::size_t>(start)] = next_label;
    for (std::size_t head = 0; head < queue_.size(); ++head) {
      const int q = queue_[head];
      const int x = q % W, y = q / W;
      const int nbr[4] = {x > 0 ? q - 1 : -1, x + 1 < W ? q + 1 : -1, y > 0 ? q - W : -1, y + 1 < H ? q + W : -1};
      for (int p : nbr) {
        if (p < 0 || relabel_[static_cast<std::size_t>(p)] >= 0 || lab[p] != old) continue;
        relabel_[static_cast<std::size_t>(p)] = next_label;
        queue_.push_back(p);
      }
    }
    if (static_cast<int>(queue_.size()) < min_size && adjacent >= 0) {
      for (int q : queue_) relabel_[static_cast<std::size_t>(q)] = adjacent;
    } else {
      ++next_label;
    }
  }
  std::memcpy(lab, relabel_.data(), P * sizeof(int32_t));
  return next_label;
}

}  // namespace agvslam::dynamic
