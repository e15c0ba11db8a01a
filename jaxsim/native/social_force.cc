// pedsim's Moussaid social force over a batch of worlds, as an XLA FFI custom call for the CPU.
//
// The same force as jaxsim/social_force.py's social_force (read its docstring for the model);
// written by hand because XLA's CPU compiler splits that pair computation into about 15 loop
// kernels and runs it at 8.6 ns per pair per core (README "Speed"). Here the worlds are the
// vector lanes: the inputs are transposed to (agent, world) blocks of 64 worlds (then 16 or 8),
// every unordered pair (i < j) is computed once for all the block's worlds at a time (the force
// on i is +w_j F, on j it is -w_i F: the model is antisymmetric), and the sums are transposed back.
// A partial last block is padded, or, for a few worlds (one alone, say), each world is computed
// with its agents as the lanes instead (one_world), in the same order and arithmetic: a world's
// result has the same bits whatever its batch size or its place in the batch (tested). Built with
// -ffp-contract=off: with fused multiply-adds the compiler contracted the two loops differently
// (2e-7 m/s^2 apart), and it costs about 5 %.
//
// Inputs (all float32, the same leading batch shape, flattened to B here):
//   x, y, vx, vy, weight: (B, A)  positions (m), velocities (m/s), source weights
//   params: (B, 5)  lambda, gamma, n', n, social force factor
// Outputs: ax, ay: (B, A)  the social acceleration (m/s^2), scaled by the force factor.
#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "xla/ffi/api/ffi.h"

namespace ffi = xla::ffi;

namespace {

// Worlds per block: 64 while as many remain, then one vector register's floats (16 with AVX-512,
// 8 otherwise), so that one world alone computes 8 or 16 lanes, not 64. Every lane runs the same
// vector instructions either way, so a world's result does not depend on its batch.
constexpr int kWideLanes = 64;
#ifdef __AVX512F__
constexpr int kNarrowLanes = 16;
#else
constexpr int kNarrowLanes = 8;
#endif
static_assert(kWideLanes % kNarrowLanes == 0, "whole vectors in both block widths");
constexpr float kEps = 1e-6f;

// max / min as selects: GCC does not vectorise fmaxf / fminf (their NaN rules) without fast math.
inline float max_of(float a, float b) { return a > b ? a : b; }
inline float min_of(float a, float b) { return a < b ? a : b; }

// exp(x) by Cephes' expf reduction and polynomial (relative error ~2e-7), vectorisable;
// x is clamped to [-87, 0]: every exponent of the Moussaid force is <= 0.
inline float exp_nonpositive(float x) {
  x = max_of(x, -87.0f);
  x = min_of(x, 0.0f);
  // n = round(x / ln 2) by the 1.5 * 2^23 trick (floorf does not vectorise without fast math).
  const float n = (x * 1.44269504088896341f + 12582912.0f) - 12582912.0f;
  float r = x - n * 0.693359375f;
  r = r + n * 2.12194440e-4f;
  float p = 1.9875691500e-4f;
  p = p * r + 1.3981999507e-3f;
  p = p * r + 8.3334519073e-3f;
  p = p * r + 4.1665795894e-2f;
  p = p * r + 1.6666665459e-1f;
  p = p * r + 5.0000001201e-1f;
  p = p * r * r + r + 1.0f;
  const int32_t bits = (static_cast<int32_t>(n) + 127) << 23;
  return p * __builtin_bit_cast(float, bits);
}

// The same 7th-order minimax arctan2 as jaxsim.social_force.fast_atan2 (max error 2e-4 rad).
inline float fast_atan2(float y, float x) {
  const float ax = std::fabs(x), ay = std::fabs(y);
  const float a = min_of(ax, ay) / max_of(max_of(ax, ay), 1e-30f);
  const float s = a * a;
  float r = ((-0.0464964749f * s + 0.15931422f) * s - 0.327622764f) * s * a + a;
  r = ay > ax ? 1.57079637f - r : r;
  r = x < 0.0f ? 3.14159274f - r : r;
  return y < 0.0f ? -r : r;
}

template <int kLanes>
struct Block {
  // (agent, lane) arrays of one block of worlds.
  std::vector<float> x, y, vx, vy, w, ax, ay;
  explicit Block(int64_t agents)
      : x(agents * kLanes), y(agents * kLanes), vx(agents * kLanes), vy(agents * kLanes), w(agents * kLanes),
        ax(agents * kLanes), ay(agents * kLanes) {}
};

template <int kLanes>
struct Params {
  alignas(64) float lambda[kLanes], inv_gamma[kLanes], gamma[kLanes], n_prime[kLanes], n[kLanes];
};

// The Moussaid force on an agent from one other (the reaction on the other is its negative):
// (dx, dy) from the agent to the other, (dvx, dvy) the agent's velocity minus the other's.
// Inline, so that the world-lane and the agent-lane loops below run the same arithmetic.
inline void moussaid(float dx, float dy, float dvx, float dvy, float lambda, float gamma, float inv_gamma,
                     float n_prime, float n, float& fx, float& fy) {
  const float dist = std::sqrt(max_of(dx * dx + dy * dy, kEps * kEps));
  const float inv = 1.0f / dist;
  const float ex = dx * inv, ey = dy * inv;
  float ix = lambda * dvx + ex, iy = lambda * dvy + ey;
  const float ilen = std::sqrt(max_of(ix * ix + iy * iy, kEps * kEps));
  const float iinv = 1.0f / ilen;
  ix *= iinv;
  iy *= iinv;
  const float theta = fast_atan2(ix * ey - iy * ex, ix * ex + iy * ey);
  const float bb = gamma * ilen;
  const float base = -dist * iinv * inv_gamma;
  const float nbt = bb * theta;
  const float a_vel = n_prime * nbt, a_ang = n * nbt;
  const float f_vel = -exp_nonpositive(base - a_vel * a_vel);
  const float sgn = theta > 0.0f ? 1.0f : (theta < 0.0f ? -1.0f : 0.0f);
  const float f_ang = -sgn * exp_nonpositive(base - a_ang * a_ang);
  fx = f_vel * ix - f_ang * iy;
  fy = f_vel * iy + f_ang * ix;
}

// Force on agent i from agent j (and its reaction) for every lane of the block. The block's
// vectors (kChains of kNarrowLanes worlds) are computed in one loop body as independent chains:
// one pair's arithmetic is a long chain of dependent operations (2 square roots, 3 divisions, 2
// exponentials), one vector's chain at a time left the processor waiting on their latency, and
// GCC's pressure-aware scheduling before register allocation (-fschedule-insns -fsched-pressure,
// native/__init__.py) interleaves the chains. Every lane runs the same operations as before, in
// the same order, so the bits are the same (6.0 -> 3.1 ns per pair with AVX2, 3.5 -> 2.3 with
// AVX-512, one core).
template <int kLanes>
inline void pair(const Params<kLanes>& p, Block<kLanes>& b, int64_t i, int64_t j) {
  const float* __restrict xi = &b.x[i * kLanes];
  const float* __restrict yi = &b.y[i * kLanes];
  const float* __restrict vxi = &b.vx[i * kLanes];
  const float* __restrict vyi = &b.vy[i * kLanes];
  const float* __restrict wi = &b.w[i * kLanes];
  const float* __restrict xj = &b.x[j * kLanes];
  const float* __restrict yj = &b.y[j * kLanes];
  const float* __restrict vxj = &b.vx[j * kLanes];
  const float* __restrict vyj = &b.vy[j * kLanes];
  const float* __restrict wj = &b.w[j * kLanes];
  float* __restrict axi = &b.ax[i * kLanes];
  float* __restrict ayi = &b.ay[i * kLanes];
  float* __restrict axj = &b.ax[j * kLanes];
  float* __restrict ayj = &b.ay[j * kLanes];
  constexpr int kChains = kLanes / kNarrowLanes, kStep = kNarrowLanes;
#pragma omp simd
  for (int t = 0; t < kStep; ++t) {
    float fx[kChains], fy[kChains];
#pragma GCC unroll 8
    for (int c = 0; c < kChains; ++c) {
      const int u = t + c * kStep;
      moussaid(xj[u] - xi[u], yj[u] - yi[u], vxi[u] - vxj[u], vyi[u] - vyj[u], p.lambda[u], p.gamma[u],
               p.inv_gamma[u], p.n_prime[u], p.n[u], fx[c], fy[c]);
    }
#pragma GCC unroll 8
    for (int c = 0; c < kChains; ++c) {
      const int u = t + c * kStep;
      axi[u] += wj[u] * fx[c];
      ayi[u] += wj[u] * fy[c];
      axj[u] -= wi[u] * fx[c];
      ayj[u] -= wi[u] * fy[c];
    }
  }
}

// One world alone with the agents as the vector lanes: for each agent i, the forces of every
// j > i at once (a vector loop), then the sums in the world-lane loop's order, so that the bits
// are the same as in a block: agent a gets the reactions of i = 0 .. a - 1 in that order (the
// vector loop's lane a, as the block's), then the forces of j = a + 1 .. in order (a scalar
// sum, as the block's). A lone world then costs about pairs / vector width force evaluations
// instead of a whole block of lanes for one useful one.
void one_world(const float* const in[5], const float* q, int64_t agents, int64_t world, float* out_x, float* out_y,
               std::vector<float>& fx, std::vector<float>& fy) {
  const float* __restrict x = in[0] + world * agents;
  const float* __restrict y = in[1] + world * agents;
  const float* __restrict vx = in[2] + world * agents;
  const float* __restrict vy = in[3] + world * agents;
  const float* __restrict w = in[4] + world * agents;
  float* __restrict ax = out_x + world * agents;
  float* __restrict ay = out_y + world * agents;
  const float lambda = q[0], gamma = q[1], inv_gamma = 1.0f / q[1], n_prime = q[2], n = q[3], factor = q[4];
  for (int64_t a = 0; a < agents; ++a) ax[a] = ay[a] = 0.0f;
  float* __restrict gx = fx.data();
  float* __restrict gy = fy.data();
  for (int64_t i = 0; i < agents; ++i) {
    const float xi = x[i], yi = y[i], vxi = vx[i], vyi = vy[i], wi = w[i];
#pragma omp simd
    for (int64_t j = i + 1; j < agents; ++j) {
      float fxj, fyj;
      moussaid(x[j] - xi, y[j] - yi, vxi - vx[j], vyi - vy[j], lambda, gamma, inv_gamma, n_prime, n, fxj, fyj);
      gx[j] = fxj;
      gy[j] = fyj;
      ax[j] -= wi * fxj;
      ay[j] -= wi * fyj;
    }
    float sx = ax[i], sy = ay[i];
    for (int64_t j = i + 1; j < agents; ++j) {
      sx += w[j] * gx[j];
      sy += w[j] * gy[j];
    }
    ax[i] = sx;
    ay[i] = sy;
  }
  for (int64_t a = 0; a < agents; ++a) {
    ax[a] = factor * ax[a];
    ay[a] = factor * ay[a];
  }
}

// One block of ``lanes`` <= kLanes worlds starting at world ``start`` (the rest of the lanes padded).
template <int kLanes>
void block(const float* const in[5], const float* par, int64_t agents, int64_t start, int64_t lanes, float* out_x,
           float* out_y) {
  Block<kLanes> b(agents);
  Params<kLanes> p;
  std::vector<float>* fields[5] = {&b.x, &b.y, &b.vx, &b.vy, &b.w};
  for (int f = 0; f < 5; ++f) {
    float* dst = fields[f]->data();
    for (int64_t t = 0; t < lanes; ++t)
      for (int64_t a = 0; a < agents; ++a) dst[a * kLanes + t] = in[f][(start + t) * agents + a];
  }
  for (int t = 0; t < kLanes; ++t) {
    const float* q = par + 5 * (start + std::min<int64_t>(t, lanes - 1));
    p.lambda[t] = q[0];
    p.gamma[t] = q[1];
    p.inv_gamma[t] = 1.0f / q[1];
    p.n_prime[t] = q[2];
    p.n[t] = q[3];
  }
  for (int64_t i = 0; i < agents; ++i)
    for (int64_t j = i + 1; j < agents; ++j) pair(p, b, i, j);
  for (int64_t t = 0; t < lanes; ++t) {
    const float factor = par[5 * (start + t) + 4];
    for (int64_t a = 0; a < agents; ++a) {
      out_x[(start + t) * agents + a] = factor * b.ax[a * kLanes + t];
      out_y[(start + t) * agents + a] = factor * b.ay[a * kLanes + t];
    }
  }
}

// The worlds [begin, end) as blocks of 64, then of one vector, then the last few (see above).
void worlds_range(const float* const in[5], const float* params, int64_t agents, int64_t begin, int64_t end,
                  float* ax, float* ay) {
  int64_t start = begin;
  for (; end - start >= kWideLanes; start += kWideLanes) block<kWideLanes>(in, params, agents, start, kWideLanes, ax, ay);
  for (; end - start >= kNarrowLanes; start += kNarrowLanes)
    block<kNarrowLanes>(in, params, agents, start, kNarrowLanes, ax, ay);
  if (start < end) {
    // The last few worlds: one block of padded lanes, or each world alone with the agents as
    // lanes (the same bits either way), whichever is faster. A world alone evaluates about
    // pairs / lanes + agents vectors of forces against a block's pairs, but costs about 3 times
    // that in its serial sums and loop tails (measured: alone wins for up to 3 worlds with
    // AVX-512 and 51 agents, 2 with AVX2).
    const int64_t left = end - start, pairs = agents * (agents - 1) / 2;
    const int64_t alone = 3 * left * (pairs / kNarrowLanes + agents);
    if (alone < pairs) {
      std::vector<float> fx(agents), fy(agents);
      for (int64_t t = start; t < end; ++t) one_world(in, params + 5 * t, agents, t, ax, ay, fx, fy);
    } else {
      block<kNarrowLanes>(in, params, agents, start, left, ax, ay);
    }
  }
}

// Chunks of whole 64-world blocks shared out over XLA's CPU threads: the calling thread and up to
// one task per other thread each take the next chunk until none is left (the last chunk also
// holds the worlds after the last whole block). A world's result does not depend on the block it
// is computed in, so the bits are those of one thread. The caller waits only for chunks another
// thread has taken and is computing, never for a task that has not started (which may never
// start while the pool is busy: XLA runs this call on one of the pool's own threads); a task
// that starts after the call has returned finds no chunk left and touches no buffer.
struct Chunks {
  std::atomic<int64_t> next{0}, done{0};
};

ffi::Error SocialForceImpl(ffi::ThreadPool pool, ffi::Buffer<ffi::F32> x, ffi::Buffer<ffi::F32> y,
                           ffi::Buffer<ffi::F32> vx, ffi::Buffer<ffi::F32> vy, ffi::Buffer<ffi::F32> weight,
                           ffi::Buffer<ffi::F32> params, ffi::ResultBuffer<ffi::F32> ax,
                           ffi::ResultBuffer<ffi::F32> ay) {
  const auto dims = x.dimensions();
  if (dims.size() < 1) return ffi::Error::InvalidArgument("social_force: x must have an agent axis");
  const int64_t agents = dims.back();
  if (agents == 0) return ffi::Error::Success();  // nothing to write
  const int64_t worlds = static_cast<int64_t>(x.element_count()) / agents;
  if (params.element_count() != static_cast<size_t>(worlds * 5))
    return ffi::Error::InvalidArgument("social_force: params must hold 5 values per world");
  const std::array<const float*, 5> in = {x.typed_data(), y.typed_data(), vx.typed_data(), vy.typed_data(),
                                          weight.typed_data()};
  const float* const p = params.typed_data();
  float* const out_x = ax->typed_data();
  float* const out_y = ay->typed_data();
  const int64_t blocks = worlds / kWideLanes;
  const int64_t threads = pool.num_threads();
  if (threads <= 1 || blocks < 2) {
    worlds_range(in.data(), p, agents, 0, worlds, out_x, out_y);
    return ffi::Error::Success();
  }
  // A few chunks a thread, so that a thread slowed by other work leaves its share to the others.
  const int64_t chunks = std::min(blocks, 4 * threads);
  auto shared = std::make_shared<Chunks>();
  auto work = [shared, in, p, out_x, out_y, agents, worlds, blocks, chunks]() {
    for (int64_t c = shared->next.fetch_add(1); c < chunks; c = shared->next.fetch_add(1)) {
      const int64_t begin = blocks * c / chunks * kWideLanes;
      const int64_t end = c == chunks - 1 ? worlds : blocks * (c + 1) / chunks * kWideLanes;
      worlds_range(in.data(), p, agents, begin, end, out_x, out_y);
      shared->done.fetch_add(1, std::memory_order_release);
    }
  };
  for (int64_t t = 1; t < std::min(threads, chunks); ++t) pool.Schedule(decltype(work)(work));
  work();
  while (shared->done.load(std::memory_order_acquire) < chunks) std::this_thread::yield();
  return ffi::Error::Success();
}

}  // namespace

XLA_FFI_DEFINE_HANDLER_SYMBOL(SocialForce, SocialForceImpl,
                              ffi::Ffi::Bind()
                                  .Ctx<ffi::ThreadPool>()
                                  .Arg<ffi::Buffer<ffi::F32>>()
                                  .Arg<ffi::Buffer<ffi::F32>>()
                                  .Arg<ffi::Buffer<ffi::F32>>()
                                  .Arg<ffi::Buffer<ffi::F32>>()
                                  .Arg<ffi::Buffer<ffi::F32>>()
                                  .Arg<ffi::Buffer<ffi::F32>>()
                                  .Ret<ffi::Buffer<ffi::F32>>()
                                  .Ret<ffi::Buffer<ffi::F32>>());
