#pragma once
// The one thread pool of the project: parallel_for splits an index range over worker threads started for the
// call (the caller is one of them). The renderer's rows, the vocabulary training's descriptors and nodes and
// agvslam-vocab's images go through it.

#include <cstddef>
#include <functional>

namespace agvslam {

// Runs f(begin, end, worker) over [0, n) in blocks of `grain` indices (the last one shorter), handed out in
// increasing order to min(threads, blocks) workers as each finishes its previous block; `worker` (0 = the
// caller's thread, < threads) tells a worker's own scratch or partial sums apart. With one worker, f runs once
// over [0, n) in the caller's thread; with n == 0 it does not run.
//
// Which worker takes which block depends on timing. A caller whose result must not depend on the thread count
// writes each index's result to its own place, or merges per-worker partial results with an operation whose
// result does not depend on the order (integer sums).
//
// The first exception f throws stops the handing out of further blocks; it is rethrown in the caller's thread
// once every worker has returned. When the system refuses another thread, fewer workers do the work.
void parallel_for(int threads, std::size_t n, std::size_t grain,
                  const std::function<void(std::size_t begin, std::size_t end, int worker)>& f);

}  // namespace agvslam
