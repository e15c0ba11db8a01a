// Dijkstra's cost-to-goal on a batch of grids, as an XLA FFI custom call for the CPU.
//
// The same graph and the same float32 arithmetic as planners/grid_planner.py's potentials (read
// its docstring): every cell a node; the move from a to its neighbour b costs
// float32(resolution * |move|) * t[b], t the traversal cost per metre of the cell entered (inf:
// impassable); a diagonal move may not pass an impassable (or off-grid) orthogonal neighbour.
// The sweeps there relax phi(a) = min_b w(a, b) + phi(b) to its fixed point; Dijkstra reaches the
// same fixed point in one pass: when a cell is settled, every neighbour that can lower it
// (fl(w + phi(b)) >= phi(b) for w >= 0) has been settled before it, so each settled value is that
// minimum over the same float32 sums, bit for bit (tested against the sweeps and scipy).
//
// The queue: buckets of width delta = half the cheapest move's cost (Dial's algorithm on a ring of
// buckets). A cell is improved only by a neighbour at least one cheapest move (2 delta) below it,
// so a neighbour that can lower any cell of the current bucket lies two buckets back or more
// (one, with the float rounding of the bucket index): every cell of the current bucket is final,
// and as each is the min of the same float32 sums, the order inside a bucket changes no bit.
// A grid whose cheapest move is 0, or whose costs spread over more than kMaxBuckets buckets,
// uses a binary heap with lazy deletion instead. The grids of the batch are independent and are
// split over threads (SOCIALNAV_PLANNER_THREADS, default the hardware's).
//
// Inputs: traversal (B, H, W) float32 (cost per metre of entering each cell, inf impassable);
//         goal (B, 2) int32 (row, col; off the grid: every cell unreachable).
// Attributes: straight_m, diagonal_m (float32: the moves' lengths, rounded as JAX rounds them),
//             connectivity (int32, 4 or 8).
// Output: phi (B, H, W) float32, inf where the goal cannot be reached.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <limits>
#include <queue>
#include <thread>
#include <utility>
#include <vector>

#include "xla/ffi/api/ffi.h"

namespace ffi = xla::ffi;

namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

struct Move {
  int di, dj;
  float length;  // metres: float32(resolution * hypot(di, dj)), as JAX rounds the Python float
};

constexpr int64_t kMaxBuckets = 1 << 16;

// One grid, padded by a ring of cells that are impassable and already settled, so that no move
// needs a bounds check: index p = (i + 1) * stride + (j + 1), stride = w + 2.
struct Padded {
  int64_t stride;
  std::vector<float> t;       // traversal, inf on the ring
  std::vector<uint8_t> wall;  // t is inf (the corner rule's test)
  std::vector<uint8_t> done;  // settled (the ring from the start)
  std::vector<float> phi;
  std::vector<int64_t> offset;  // of each move
};

// Relax phi[a] through b (settled at d) for every move a -> b. Branch-free over the moves (which
// of them improve a cell is data and unpredictable): the improved cells are gathered, then pushed.
// K: the number of moves (8 or 4, the first K of the padded grid's move table), a constant so
// that the loop unrolls.
template <int K, typename Push>
inline void relax_into(Padded& g, const Move* moves, int64_t b, float d, Push push) {
  const float tb = g.t[b];
  int64_t cell[K];
  float value[K];
  int n = 0;
  for (int k = 0; k < K; ++k) {
    const Move& m = moves[k];
    const int64_t a = b - g.offset[k];
    const bool corner = m.di && m.dj && (g.wall[a + m.di * g.stride] | g.wall[a + m.dj]);
    const float candidate = m.length * tb + d;  // -ffp-contract=off: two roundings, as in JAX
    const bool better = !g.done[a] & !corner & (candidate < g.phi[a]);
    g.phi[a] = better ? candidate : g.phi[a];
    cell[n] = a, value[n] = candidate;
    n += better;
  }
  for (int k = 0; k < n; ++k) push(cell[k], value[k]);
}

template <int K>
void by_heap(Padded& g, const Move* moves, int64_t goal) {
  using Entry = std::pair<float, int64_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  heap.emplace(0.0f, goal);
  while (!heap.empty()) {
    const auto [d, b] = heap.top();
    heap.pop();
    if (g.done[b]) continue;
    g.done[b] = 1;
    relax_into<K>(g, moves, b, d, [&](int64_t a, float c) { heap.emplace(c, a); });
  }
}

template <int K>
void by_buckets(Padded& g, const Move* moves, int64_t goal, float delta, int64_t n_buckets) {
  int64_t size = 1;  // a power of two, so that the ring's index is a mask, not a division
  while (size < n_buckets) size *= 2;
  const int64_t mask = size - 1;
  std::vector<std::vector<int32_t>> ring(size);
  const float inv = 1.0f / delta;
  int64_t pending = 1;
  ring[0].push_back(static_cast<int32_t>(goal));
  for (int64_t current = 0; pending > 0; ++current) {
    std::vector<int32_t>& bucket = ring[current & mask];
    // Relaxations land two buckets on or more (at most n_buckets - 1 on): never in this vector.
    for (size_t k = 0; k < bucket.size(); ++k) {
      const int64_t b = bucket[k];
      --pending;
      if (g.done[b]) continue;
      g.done[b] = 1;
      relax_into<K>(g, moves, b, g.phi[b], [&](int64_t a, float c) {
        ring[static_cast<int64_t>(c * inv) & mask].push_back(static_cast<int32_t>(a));
        ++pending;
      });
    }
    bucket.clear();
  }
}

void one_grid(const float* t, const int32_t* goal, int64_t h, int64_t w, const std::vector<Move>& moves, float* phi,
              Padded& g) {
  std::fill(phi, phi + h * w, kInf);
  const int64_t gi = goal[0], gj = goal[1];
  if (gi < 0 || gi >= h || gj < 0 || gj >= w) return;
  const int64_t stride = w + 2, size = (h + 2) * stride;
  g.stride = stride;
  g.t.assign(size, kInf);
  g.wall.assign(size, 1);
  g.done.assign(size, 1);
  g.phi.assign(size, kInf);
  float t_min = kInf, t_max = 0.0f;
  for (int64_t i = 0; i < h; ++i)
    for (int64_t j = 0; j < w; ++j) {
      const float v = t[i * w + j];
      const int64_t p = (i + 1) * stride + j + 1;
      g.t[p] = v;
      g.wall[p] = std::isinf(v);
      g.done[p] = 0;
      if (!std::isinf(v)) t_min = std::min(t_min, v), t_max = std::max(t_max, v);
    }
  g.offset.clear();
  float shortest = kInf, longest = 0.0f;
  for (const Move& m : moves) {
    g.offset.push_back(m.di * stride + m.dj);
    shortest = std::min(shortest, m.length), longest = std::max(longest, m.length);
  }
  const int64_t start = (gi + 1) * stride + gj + 1;
  g.phi[start] = 0.0f;
  const float delta = 0.5f * shortest * t_min;
  const double spread = static_cast<double>(longest) * t_max / delta;
  if (size < (int64_t{1} << 31) && delta > 0.0f && std::isfinite(delta) && spread < kMaxBuckets)
    moves.size() == 8 ? by_buckets<8>(g, moves.data(), start, delta, static_cast<int64_t>(spread) + 3)
                      : by_buckets<4>(g, moves.data(), start, delta, static_cast<int64_t>(spread) + 3);
  else
    moves.size() == 8 ? by_heap<8>(g, moves.data(), start) : by_heap<4>(g, moves.data(), start);
  for (int64_t i = 0; i < h; ++i)
    std::copy_n(g.phi.begin() + (i + 1) * stride + 1, w, phi + i * w);
}

int threads_for(int64_t grids) {
  int n = static_cast<int>(std::thread::hardware_concurrency());
  if (const char* s = std::getenv("SOCIALNAV_PLANNER_THREADS")) n = std::atoi(s);
  return static_cast<int>(std::clamp<int64_t>(n, 1, std::max<int64_t>(grids, 1)));
}

// The path down the potential from `start`, as planners/grid_planner.py's descend takes it: at
// each step the move with the least w + phi (the first in move order on a tie), while that is
// finite and the goal not reached; `steps` steps, the last cell repeated once it stops. A start off
// the grid, or a goal off it, stays where it is. Returns the number of distinct cells.
int32_t descend(const Padded& g, const std::vector<Move>& moves, int64_t h, int64_t w, const int32_t* start,
                const int32_t* goal, int32_t steps, int32_t* path) {
  int64_t i = start[0], j = start[1];
  const bool on = i >= 0 && i < h && j >= 0 && j < w && goal[0] >= 0 && goal[0] < h && goal[1] >= 0 && goal[1] < w;
  int32_t length = 1;
  path[0] = static_cast<int32_t>(i), path[1] = static_cast<int32_t>(j);
  for (int32_t s = 1; s <= steps; ++s) {
    if (on && !(i == goal[0] && j == goal[1])) {
      const int64_t p = (i + 1) * g.stride + j + 1;
      float best = kInf;
      int best_k = -1;
      for (size_t k = 0; k < moves.size(); ++k) {
        const Move& m = moves[k];
        const int64_t nb = p + g.offset[k];
        float weight = g.wall[nb] ? kInf : m.length * g.t[nb];
        if (m.di && m.dj && (g.wall[p + m.di * g.stride] | g.wall[p + m.dj])) weight = kInf;
        const float value = weight + g.phi[nb];
        if (best_k < 0 || value < best) best = value, best_k = static_cast<int>(k);
      }
      if (std::isfinite(best)) {
        i += moves[best_k].di, j += moves[best_k].dj;
        ++length;
      }
    }
    path[2 * s] = static_cast<int32_t>(i), path[2 * s + 1] = static_cast<int32_t>(j);
  }
  return length;
}

std::vector<Move> moves_for(int32_t connectivity, float straight_m, float diagonal_m) {
  std::vector<Move> moves;  // planners/grid_planner.py's MOVES_8 / MOVES_4 order
  for (int di = -1; di <= 1; ++di)
    for (int dj = -1; dj <= 1; ++dj) {
      if ((di == 0 && dj == 0) || (connectivity == 4 && di && dj)) continue;
      moves.push_back({di, dj, di && dj ? diagonal_m : straight_m});
    }
  return moves;
}

// Runs grid(b, scratch) for every grid of the batch, the grids dealt round-robin to the threads.
template <typename Grid>
void over_batch(int64_t grids, Grid grid) {
  const int n_threads = threads_for(grids);
  auto run = [&](int k) {
    Padded scratch;  // reused by the thread's grids
    for (int64_t b = k; b < grids; b += n_threads) grid(b, scratch);
  };
  if (n_threads == 1) {
    run(0);
    return;
  }
  std::vector<std::thread> pool;
  for (int k = 0; k < n_threads; ++k) pool.emplace_back(run, k);
  for (auto& th : pool) th.join();
}

ffi::Error check(const ffi::Buffer<ffi::F32>& traversal, size_t goal_count, int32_t connectivity, int64_t& h,
                 int64_t& w, int64_t& grids) {
  const auto dims = traversal.dimensions();
  if (dims.size() < 2) return ffi::Error::InvalidArgument("grid_dijkstra: traversal must be (..., H, W)");
  if (connectivity != 4 && connectivity != 8)
    return ffi::Error::InvalidArgument("grid_dijkstra: connectivity must be 4 or 8");
  h = dims[dims.size() - 2], w = dims[dims.size() - 1];
  grids = h && w ? static_cast<int64_t>(traversal.element_count()) / (h * w) : 0;
  if (goal_count != static_cast<size_t>(2 * grids))
    return ffi::Error::InvalidArgument("grid_dijkstra: goal must hold (row, col) per grid");
  return ffi::Error::Success();
}

ffi::Error GridDijkstraImpl(ffi::Buffer<ffi::F32> traversal, ffi::Buffer<ffi::S32> goal, float straight_m,
                            float diagonal_m, int32_t connectivity, ffi::ResultBuffer<ffi::F32> phi) {
  int64_t h, w, grids;
  if (auto e = check(traversal, goal.element_count(), connectivity, h, w, grids); e.failure()) return e;
  const auto moves = moves_for(connectivity, straight_m, diagonal_m);
  const float* t = traversal.typed_data();
  const int32_t* g = goal.typed_data();
  float* out = phi->typed_data();
  over_batch(grids, [&](int64_t b, Padded& scratch) {
    one_grid(t + b * h * w, g + 2 * b, h, w, moves, out + b * h * w, scratch);
  });
  return ffi::Error::Success();
}

ffi::Error GridPlanImpl(ffi::Buffer<ffi::F32> traversal, ffi::Buffer<ffi::S32> start, ffi::Buffer<ffi::S32> goal,
                        float straight_m, float diagonal_m, int32_t connectivity, int32_t steps,
                        ffi::ResultBuffer<ffi::F32> phi, ffi::ResultBuffer<ffi::S32> path,
                        ffi::ResultBuffer<ffi::S32> length) {
  int64_t h, w, grids;
  if (auto e = check(traversal, goal.element_count(), connectivity, h, w, grids); e.failure()) return e;
  if (start.element_count() != goal.element_count())
    return ffi::Error::InvalidArgument("grid_plan: start must hold (row, col) per grid");
  if (path->element_count() != static_cast<size_t>(grids * (steps + 1) * 2))
    return ffi::Error::InvalidArgument("grid_plan: path must be (..., steps + 1, 2)");
  const auto moves = moves_for(connectivity, straight_m, diagonal_m);
  const float* t = traversal.typed_data();
  const int32_t *s = start.typed_data(), *g = goal.typed_data();
  float* out = phi->typed_data();
  int32_t *cells = path->typed_data(), *n = length->typed_data();
  over_batch(grids, [&](int64_t b, Padded& scratch) {
    one_grid(t + b * h * w, g + 2 * b, h, w, moves, out + b * h * w, scratch);
    n[b] = descend(scratch, moves, h, w, s + 2 * b, g + 2 * b, steps, cells + b * (steps + 1) * 2);
  });
  return ffi::Error::Success();
}

}  // namespace

XLA_FFI_DEFINE_HANDLER_SYMBOL(GridDijkstra, GridDijkstraImpl,
                              ffi::Ffi::Bind()
                                  .Arg<ffi::Buffer<ffi::F32>>()
                                  .Arg<ffi::Buffer<ffi::S32>>()
                                  .Attr<float>("straight_m")
                                  .Attr<float>("diagonal_m")
                                  .Attr<int32_t>("connectivity")
                                  .Ret<ffi::Buffer<ffi::F32>>());

XLA_FFI_DEFINE_HANDLER_SYMBOL(GridPlan, GridPlanImpl,
                              ffi::Ffi::Bind()
                                  .Arg<ffi::Buffer<ffi::F32>>()
                                  .Arg<ffi::Buffer<ffi::S32>>()
                                  .Arg<ffi::Buffer<ffi::S32>>()
                                  .Attr<float>("straight_m")
                                  .Attr<float>("diagonal_m")
                                  .Attr<int32_t>("connectivity")
                                  .Attr<int32_t>("steps")
                                  .Ret<ffi::Buffer<ffi::F32>>()
                                  .Ret<ffi::Buffer<ffi::S32>>()
                                  .Ret<ffi::Buffer<ffi::S32>>());
