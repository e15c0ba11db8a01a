// Dijkstra's cost-to-goal on a batch of grids, as an XLA FFI custom call for the CPU.
//
// The same graph and the same float32 arithmetic as planners/global_planners/grid_planner.py's potentials (read
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
#include <cstring>
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

typedef float V4f __attribute__((vector_size(16)));
typedef int32_t V4i __attribute__((vector_size(16)));

struct Bucket;

// One grid, padded by a ring of cells that are impassable and already settled, so that no move
// needs a bounds check: index p = (i + 1) * stride + (j + 1), stride = w + 2.
struct Padded {
  int64_t stride;
  std::vector<float> t;       // traversal, inf on the ring
  std::vector<uint8_t> wall;  // t is inf (the corner rule's test)
  std::vector<float> phi;     // the potential; -phi once settled
  std::vector<int64_t> offset;  // of each move (the path's descent)
  V4f length[3];                // metres of the move a -> b, a in b's row above, own, below (lanes: columns j-1..j+2)
  V4i open_lanes[16][3];        // by the walls N, S, W, E of b: which of those moves are allowed (-1) or not (0)
  std::vector<Bucket> ring;     // the bucket queue, kept allocated between grids
};

inline V4f load4(const float* p) {
  V4f v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

inline void store4(float* p, V4f v) { std::memcpy(p, &v, sizeof v); }

inline uint32_t lane_bits(V4i m) {
#if defined(__SSE__)
  return static_cast<uint32_t>(__builtin_ia32_movmskps(reinterpret_cast<V4f>(m)));
#else
  return (m[0] & 1u) | (m[1] & 2u) | (m[2] & 4u) | (m[3] & 8u);
#endif
}

// Relaxes phi[a] through b (settled at d) for every move a -> b, the neighbours a of b taken as
// three rows of four cells (b's row above, its own, below; from the column left of b), one
// vector each: the candidates len(a -> b) * t[b] + d (the same two float32 roundings per move as
// in JAX: -ffp-contract=off) replace phi[a] where they are lower and the move is open (lanes
// off: b itself, the fourth column, a move the corner rule or the connectivity forbids; a
// settled cell holds -phi, so no candidate beats it). Branch-free (which neighbours improve is
// data, unpredictable). Returns the improved cells as a 12-bit mask: lane x of row r at bit
// 4 r + x, the cell b + (r - 1) * stride + x - 1.
inline uint32_t relax(Padded& g, int64_t b, float d) {
  const float tb = g.t[b];
  const int mask = g.wall[b - g.stride] | g.wall[b + g.stride] << 1 | g.wall[b - 1] << 2 | g.wall[b + 1] << 3;
  const V4f base = {d, d, d, d};
  const V4f tv = {tb, tb, tb, tb};
  uint32_t bits = 0;
  for (int r = 0; r < 3; ++r) {
    float* row = g.phi.data() + b + (r - 1) * g.stride - 1;
    const V4f old = load4(row);
    const V4f candidate = g.length[r] * tv + base;
    const V4i better = (candidate < old) & g.open_lanes[mask][r];
    store4(row, better ? candidate : old);
    bits |= lane_bits(better) << (4 * r);
  }
  return bits;
}

// The cell of bit `bit` of relax's mask.
inline int64_t lane_cell(const Padded& g, int64_t b, int bit) { return b + (bit / 4 - 1) * g.stride + bit % 4 - 1; }

void by_heap(Padded& g, int64_t goal) {
  using Entry = std::pair<float, int64_t>;
  std::priority_queue<Entry, std::vector<Entry>, std::greater<Entry>> heap;
  heap.emplace(0.0f, goal);
  while (!heap.empty()) {
    const auto [d, b] = heap.top();
    heap.pop();
    if (std::signbit(g.phi[b])) continue;
    g.phi[b] = -d;
    for (uint32_t bits = relax(g, b, d); bits; bits &= bits - 1) {
      const int64_t a = lane_cell(g, b, __builtin_ctz(bits));
      heap.emplace(g.phi[a], a);
    }
  }
}

// A bucket of the ring: its cells, first n of `cells` (kept allocated between grids).
struct Bucket {
  std::vector<int32_t> cells;
  size_t n = 0;
  int32_t* room(size_t k) {  // space for k more cells
    if (n + k > cells.size()) cells.resize(2 * cells.size() + 64);
    return cells.data() + n;
  }
};

// Appends to `bucket` the cells of `bits` (relax's mask) among the four at `position` (the cells
// b + offset), without a branch per cell: each is written, and counted if its bit is set.
inline void push4(Bucket& bucket, uint32_t bits, const int (&position)[4], const int64_t (&offset)[4], int64_t b) {
  int32_t* out = bucket.room(4);
  size_t n = 0;
  for (int k = 0; k < 4; ++k) {
    out[n] = static_cast<int32_t>(b + offset[k]);
    n += (bits >> position[k]) & 1u;
  }
  bucket.n += n;
}

// The straight moves' candidates are all one value, fl(fl(straight_m t[b]) + d), and the
// diagonals' another: the improved cells go to two buckets, four cells each at most.
void by_buckets(Padded& g, int64_t goal, float delta, int64_t n_buckets) {
  int64_t size = 1;  // a power of two, so that the ring's index is a mask, not a division
  while (size < n_buckets) size *= 2;
  const int64_t mask = size - 1;
  std::vector<Bucket>& ring = g.ring;
  if (static_cast<int64_t>(ring.size()) < size) ring.resize(size);
  for (auto& r : ring) r.n = 0;
  const float inv = 1.0f / delta;
  const int64_t s = g.stride;
  static constexpr int kStraight[4] = {1, 4, 6, 9}, kDiagonal[4] = {0, 2, 8, 10};
  const int64_t straight_offset[4] = {-s, -1, 1, s}, diagonal_offset[4] = {-s - 1, -s + 1, s - 1, s + 1};
  const float straight_m = g.length[0][1], diagonal_m = g.length[0][0];  // 0 when 4-connected (lanes off)
  int64_t pending = 1;
  *ring[0].room(1) = static_cast<int32_t>(goal);
  ring[0].n = 1;
  for (int64_t current = 0; pending > 0; ++current) {
    Bucket& bucket = ring[current & mask];
    // Relaxations land one bucket on or more (at most n_buckets - 1 on): never in this one.
    for (size_t k = 0; k < bucket.n; ++k) {
      const int64_t b = bucket.cells[k];
      --pending;
      const float d = g.phi[b];
      if (std::signbit(d)) continue;
      g.phi[b] = -d;
      const uint32_t bits = relax(g, b, d);
      pending += __builtin_popcount(bits);
      const float tb = g.t[b];
      push4(ring[static_cast<int64_t>((straight_m * tb + d) * inv) & mask], bits, kStraight, straight_offset, b);
      push4(ring[static_cast<int64_t>((diagonal_m * tb + d) * inv) & mask], bits, kDiagonal, diagonal_offset, b);
    }
    bucket.n = 0;
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
  g.phi.assign(size + 2, -kInf);  // settled cells hold -phi (the ring: settled, unreachable); + 2: the
                                  // last row's vectors read two cells past the ring
  float t_min = kInf, t_max = 0.0f;
  for (int64_t i = 0; i < h; ++i)
    for (int64_t j = 0; j < w; ++j) {
      const float v = t[i * w + j];
      const int64_t p = (i + 1) * stride + j + 1;
      g.t[p] = v;
      g.wall[p] = std::isinf(v);
      g.phi[p] = kInf;
      if (!std::isinf(v)) t_min = std::min(t_min, v), t_max = std::max(t_max, v);
    }
  g.offset.clear();
  float shortest = kInf, longest = 0.0f;
  for (const Move& m : moves) {
    g.offset.push_back(m.di * stride + m.dj);
    shortest = std::min(shortest, m.length), longest = std::max(longest, m.length);
  }
  for (int r = 0; r < 3; ++r)  // relax's lanes: length and whether open, by the walls around b
    for (int x = 0; x < 4; ++x) {
      g.length[r][x] = 0.0f;
      for (int mask = 0; mask < 16; ++mask) g.open_lanes[mask][r][x] = 0;
      for (const Move& m : moves)  // a = b + (r - 1, x - 1): the move a -> b is (1 - r, 1 - x)
        if (m.di == 1 - r && m.dj == 1 - x) {
          g.length[r][x] = m.length;
          for (int mask = 0; mask < 16; ++mask) {
            const bool blocked = m.di && m.dj && ((mask & (m.di == 1 ? 1 : 2)) || (mask & (m.dj == 1 ? 4 : 8)));
            g.open_lanes[mask][r][x] = blocked ? 0 : -1;
          }
        }
    }
  const int64_t start = (gi + 1) * stride + gj + 1;
  g.phi[start] = 0.0f;
  const float delta = 0.5f * shortest * t_min;
  const double spread = static_cast<double>(longest) * t_max / delta;
  if (size < (int64_t{1} << 31) && delta > 0.0f && std::isfinite(delta) && spread < kMaxBuckets)
    by_buckets(g, start, delta, static_cast<int64_t>(spread) + 3);
  else
    by_heap(g, start);
  for (float& v : g.phi) v = std::fabs(v);  // settled: -phi -> phi; the ring: -inf -> inf
  for (int64_t i = 0; i < h; ++i)
    std::copy_n(g.phi.begin() + (i + 1) * stride + 1, w, phi + i * w);
}

int threads_for(int64_t grids) {
  int n = static_cast<int>(std::thread::hardware_concurrency());
  if (const char* s = std::getenv("SOCIALNAV_PLANNER_THREADS")) n = std::atoi(s);
  return static_cast<int>(std::clamp<int64_t>(n, 1, std::max<int64_t>(grids, 1)));
}

// The path down the potential from `start`, as planners/global_planners/grid_planner.py's descend takes it: at
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
  std::vector<Move> moves;  // planners/global_planners/grid_planner.py's MOVES_8 / MOVES_4 order
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
