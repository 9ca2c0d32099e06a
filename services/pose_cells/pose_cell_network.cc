#include "services/pose_cells/pose_cell_network.h"

#include "common/math/pose2d_proto.h"
#include "services/pose_cells/boundary_match.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <string>
#include <unordered_set>
#include <utility>

#if defined(__x86_64__)
#include <immintrin.h>
#endif

namespace rslam::pose_cells {
namespace {

constexpr double kTwoPi = 2.0 * std::numbers::pi;

// 1-D Gaussian weights exp(-(i - c)^2 / (2 var^2)) normalised to sum 1. OpenRatSLAM builds the
// 3-D kernel as exp(-|r|^2 / (2 var^2)) normalised over the cube, which is exactly the outer
// product of three of these.
std::vector<float> GaussianWeights(int dim, double var) {
  std::vector<double> w(dim);
  const int c = dim / 2;
  double total = 0.0;
  for (int i = 0; i < dim; ++i) {
    w[i] = std::exp(-static_cast<double>((i - c) * (i - c)) / (2.0 * var * var));
    total += w[i];
  }
  std::vector<float> out(dim);
  for (int i = 0; i < dim; ++i) out[i] = static_cast<float>(w[i] / total);
  return out;
}

// i mod n in [0, n). Indices are almost always within one lap of the range: those are wrapped
// without a division (the passes wrap every tap of every row).
inline int Wrap(int i, int n) {
  if (i >= 0) {
    if (i < n) return i;
    if (i < 2 * n) return i - n;
  } else if (i >= -n) {
    return i + n;
  }
  i %= n;
  return i < 0 ? i + n : i;
}

inline double WrapReal(double v, double n) {
  v = std::fmod(v, n);
  if (v < 0) v += n;
  if (v >= n) v -= n;
  return v;
}

// dst[x] += w * src[x + shift] for x in [lo, hi). The buffers never alias; saying so lets the
// compiler vectorise without run-time overlap checks.
inline void AddScaled(float* __restrict dst, const float* __restrict src, float w, int lo, int hi,
                      int shift) {
  for (int x = lo; x < hi; ++x) dst[x] += w * src[x + shift];
}

// dst[x] = w[0] * src[0][x] + w[1] * src[1][x] + ..., added left to right starting from 0, for
// x in [lo, hi): bit for bit what AddScaled passes tap after tap into a zeroed row give, with
// one store per cell instead of a load and a store per tap. Each cell is computed on its own
// (no fused multiply-add), so SSE2, AVX2 and plain C++ give the same floats.
void WeightedSumPortable(float* __restrict dst, const float* const* src, const float* w, int taps, int lo, int hi) {
  int x = lo;
#if defined(__SSE2__)
  for (; x + 4 <= hi; x += 4) {
    __m128 acc = _mm_setzero_ps();
    for (int k = 0; k < taps; ++k) acc = _mm_add_ps(acc, _mm_mul_ps(_mm_set1_ps(w[k]), _mm_loadu_ps(src[k] + x)));
    _mm_storeu_ps(dst + x, acc);
  }
#endif
  for (; x < hi; ++x) {
    float acc = 0.0f;
    for (int k = 0; k < taps; ++k) acc += w[k] * src[k][x];
    dst[x] = acc;
  }
}

#if defined(__x86_64__)
// kBlocks vectors of 8 cells from x on, each with its own accumulator: the taps are added to
// each cell in the same order as one vector at a time would, but the kBlocks addition chains
// are independent, so the adds overlap instead of waiting on each other's latency. The last
// block loads and stores only the lanes in last_mask (nothing read or written past them).
template <int kBlocks>
__attribute__((target("avx2"))) inline void WeightedSumBlocksAvx2(float* __restrict dst, const float* const* src,
                                                                  const float* w, int taps, int x, __m256i last_mask) {
  __m256 acc[kBlocks];
  for (int b = 0; b < kBlocks; ++b) acc[b] = _mm256_setzero_ps();
  for (int k = 0; k < taps; ++k) {
    const __m256 weight = _mm256_set1_ps(w[k]);
    const float* s = src[k] + x;
    for (int b = 0; b + 1 < kBlocks; ++b) {
      acc[b] = _mm256_add_ps(acc[b], _mm256_mul_ps(weight, _mm256_loadu_ps(s + 8 * b)));
    }
    acc[kBlocks - 1] = _mm256_add_ps(
        acc[kBlocks - 1], _mm256_mul_ps(weight, _mm256_maskload_ps(s + 8 * (kBlocks - 1), last_mask)));
  }
  for (int b = 0; b + 1 < kBlocks; ++b) _mm256_storeu_ps(dst + x + 8 * b, acc[b]);
  _mm256_maskstore_ps(dst + x + 8 * (kBlocks - 1), last_mask, acc[kBlocks - 1]);
}

__attribute__((target("avx2"))) void WeightedSumAvx2(float* __restrict dst, const float* const* src, const float* w,
                                                     int taps, int lo, int hi) {
  const __m256i all = _mm256_set1_epi32(-1);
  int x = lo;
  for (; hi - x > 32; x += 32) WeightedSumBlocksAvx2<4>(dst, src, w, taps, x, all);
  // The last 1..32 cells in 1..4 blocks, the last one masked to the cells that remain.
  const int remaining = hi - x;
  if (remaining <= 0) return;
  const int blocks = (remaining + 7) / 8;
  const __m256i lanes = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  const __m256i last_mask = _mm256_cmpgt_epi32(_mm256_set1_epi32(remaining - 8 * (blocks - 1)), lanes);
  switch (blocks) {
    case 1: WeightedSumBlocksAvx2<1>(dst, src, w, taps, x, last_mask); break;
    case 2: WeightedSumBlocksAvx2<2>(dst, src, w, taps, x, last_mask); break;
    case 3: WeightedSumBlocksAvx2<3>(dst, src, w, taps, x, last_mask); break;
    default: WeightedSumBlocksAvx2<4>(dst, src, w, taps, x, last_mask); break;
  }
}
#endif

using WeightedSumFunction = void (*)(float* __restrict, const float* const*, const float*, int, int, int);

// AVX2 when the CPU has it (decided once; the project is not built for a particular CPU).
WeightedSumFunction BestWeightedSum() {
#if defined(__x86_64__)
  static const WeightedSumFunction best = [] {
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") ? &WeightedSumAvx2 : &WeightedSumPortable;
  }();
  return best;
#else
  return &WeightedSumPortable;
#endif
}

void WeightedSum(float* __restrict dst, const float* const* src, const float* w, int taps, int lo, int hi) {
  static const WeightedSumFunction best = BestWeightedSum();
  best(dst, src, w, taps, lo, hi);
}

// Per-cell loops over one run of a row. Written so the compiler vectorises them (no aliasing,
// no branches): each cell's result is computed on its own, so vector and scalar code agree.

// member[x] |= (e[x] >= global and e[x] > 0) for x in [b, end); non-zero when any cell passed.
uint8_t MarkStrong(const float* __restrict e, uint8_t* __restrict member, float global, int b, int end) {
  uint8_t any = 0;
  for (int x = b; x < end; ++x) {
    const uint8_t strong = static_cast<uint8_t>((e[x] >= global) & (e[x] > 0.0f));
    member[x] |= strong;
    any |= strong;
  }
  return any;
}

// member[x] |= (row[x] != 0) for x in [b, end); non-zero when any cell is non-zero.
uint8_t MarkNonZero(const float* __restrict row, uint8_t* __restrict member, int b, int end) {
  uint8_t any = 0;
  for (int x = b; x < end; ++x) {
    const uint8_t non_zero = static_cast<uint8_t>(row[x] != 0.0f);
    member[x] |= non_zero;
    any |= non_zero;
  }
  return any;
}

// a[x] = max(e[x] - inh[x] - global, 0) and inh[x] = 0 for x in [b, end). The same float as
// "v = e - inh; v >= global ? v - global : 0": v - global is >= +0 exactly when v >= global
// (IEEE subtraction of distinct finite floats never rounds to zero), and +0 when equal.
void ClampedDifference(const float* __restrict e, float* __restrict inh, float* __restrict a, float global, int b,
                       int end) {
  for (int x = b; x < end; ++x) {
    a[x] = std::max(e[x] - inh[x] - global, 0.0f);
    inh[x] = 0.0f;
  }
}

// row[x] = 0 for x in [b, end). Runs are a few cells long and there are hundreds per step: an
// inline vector loop, not the library memset call GCC would otherwise turn the loop into.
#if defined(__GNUC__) && !defined(__clang__)
__attribute__((optimize("no-tree-loop-distribute-patterns")))
#endif
inline void ZeroCells(float* __restrict row, int b, int end) {
  for (int x = b; x < end; ++x) row[x] = 0.0f;
}

double MinDelta(double a, double b, double n) {
  const double d = std::abs(a - b);
  return std::min(d, n - d);
}

}  // namespace

PoseCellNetwork::PoseCellNetwork(const PoseCellConfig& config)
    : config_((config.Validate(), config)),
      dim_xy_(config.pc_dim_xy),
      dim_th_(config.pc_dim_th),
      excite_w_(GaussianWeights(config.pc_w_e_dim, config.pc_w_e_var)),
      inhibit_w_(GaussianWeights(config.pc_w_i_dim, config.pc_w_i_var)) {
  const size_t cells = static_cast<size_t>(dim_xy_) * dim_xy_ * dim_th_;
  activity_.assign(cells, 0.0f);
  buf_a_.assign(cells, 0.0f);
  buf_b_.assign(cells, 0.0f);
  buf_c_.assign(cells, 0.0f);
  for (RowFlags* r : {&rows_act_, &rows_a_, &rows_b_, &rows_c_, &rows_candidate_}) {
    r->assign(static_cast<size_t>(dim_xy_) * dim_th_, RowExtent{});
  }
  for (AxisSet* s : {&xs_, &ys_, &ex_xs_, &ex_ys_, &tmp_xs_, &tmp_ys_}) {
    s->Reset(dim_xy_);
    s->index.reserve(dim_xy_);
  }
  for (AxisSet* s : {&ts_, &ex_ts_, &tmp_ts_}) {
    s->Reset(dim_th_);
    s->index.reserve(dim_th_);
  }
  avg_x_.assign(dim_xy_, 0.0);
  avg_y_.assign(dim_xy_, 0.0);
  avg_th_.assign(dim_th_, 0.0);
  // OpenRatSLAM starts with all activity in the centre cell.
  InjectEnergy(dim_xy_ / 2, dim_xy_ / 2, dim_th_ / 2, 1.0);
  best_ = {static_cast<double>(dim_xy_ / 2), static_cast<double>(dim_xy_ / 2),
           static_cast<double>(dim_th_ / 2)};
}

// ---------------------------------------------------------------------------------------------
// Region bookkeeping

void PoseCellNetwork::Dilate(const AxisSet& in, int n, int lo, int hi, AxisSet& out) const {
  std::fill(out.member.begin(), out.member.end(), 0);
  out.index.clear();
  if (lo + hi + 1 >= n) {
    std::fill(out.member.begin(), out.member.end(), 1);
  } else {
    for (int i : in.index) {
      for (int d = -lo; d <= hi; ++d) out.member[Wrap(i + d, n)] = 1;
    }
  }
  out.Finish();
}

void PoseCellNetwork::ZeroRegion(std::vector<float>& buf, const AxisSet& xs, const AxisSet& ys,
                                 const AxisSet& ts) {
  for (int t : ts.index) {
    for (int y : ys.index) {
      float* row = &buf[Flat(0, y, t)];
      for (auto [b, e] : xs.runs) ZeroCells(row, b, e);
    }
  }
}

void PoseCellNetwork::RecomputeSupport(const AxisSet& xs, const AxisSet& ys, const AxisSet& ts,
                                       const RowFlags* candidates) {
  // xs/ys/ts may alias scratch sets, never xs_/ys_/ts_ themselves.
  std::fill(xs_.member.begin(), xs_.member.end(), 0);
  std::fill(ys_.member.begin(), ys_.member.end(), 0);
  std::fill(ts_.member.begin(), ts_.member.end(), 0);
  for (int t : ts.index) {
    for (int y : ys.index) {
      const RowExtent scan = candidates ? (*candidates)[Row(y, t)] : RowExtent{0, dim_xy_};
      if (scan.empty()) {
        rows_act_[Row(y, t)] = RowExtent{};
        continue;
      }
      const float* row = &activity_[Flat(0, y, t)];
      uint8_t any = 0;
      for (auto [b, e] : xs.runs) {
        any |= MarkNonZero(row, xs_.member.data(), std::max(b, scan.lo), std::min(e, scan.hi));
      }
      if (!any) {
        rows_act_[Row(y, t)] = RowExtent{};
        continue;
      }
      // The row's first and last non-zero cells (runs ascend): found from each end.
      int lo = dim_xy_, hi = 0;
      for (auto it = xs.runs.begin(); it != xs.runs.end() && lo == dim_xy_; ++it) {
        for (int x = std::max(it->first, scan.lo); x < std::min(it->second, scan.hi); ++x) {
          if (row[x] != 0.0f) {
            lo = x;
            break;
          }
        }
      }
      for (auto it = xs.runs.rbegin(); it != xs.runs.rend() && hi == 0; ++it) {
        for (int x = std::min(it->second, scan.hi) - 1; x >= std::max(it->first, scan.lo); --x) {
          if (row[x] != 0.0f) {
            hi = x + 1;
            break;
          }
        }
      }
      rows_act_[Row(y, t)] = RowExtent{lo, hi};
      ys_.member[y] = ts_.member[t] = 1;
    }
  }
  xs_.Finish();
  ys_.Finish();
  ts_.Finish();
}

// ---------------------------------------------------------------------------------------------
// Separable convolution passes. Input buffers are zero outside their region, so a gather that
// reads outside it reads zeros; output buffers are zero on entry (all scratch buffers are kept
// clean), so passes may accumulate.

void PoseCellNetwork::ConvolveX(const std::vector<float>& in, const RowFlags& in_rows,
                                std::vector<float>& out, RowFlags& out_rows,
                                const std::vector<float>& w, const AxisSet& xs_out,
                                const AxisSet& ys, const AxisSet& ts) {
  const int k_dim = static_cast<int>(w.size());
  const int c = k_dim / 2;
  const int n = dim_xy_;
  // padded_row_[i] = src[(i - c) wrapped]: tap k of cell x reads padded_row_[x + k].
  padded_row_.resize(static_cast<size_t>(n) + 2 * c);
  const float* taps[kMaxTaps];
  for (int k = 0; k < k_dim; ++k) taps[k] = padded_row_.data() + k;
  for (int t : ts.index) {
    for (int y : ys.index) {
      const RowExtent ein = in_rows[Row(y, t)];
      if (ein.empty()) {
        out_rows[Row(y, t)] = RowExtent{};
        continue;
      }
      const RowExtent eout = (ein.lo - c < 0 || ein.hi + c > n) ? RowExtent{0, n}
                                                               : RowExtent{ein.lo - c, ein.hi + c};
      out_rows[Row(y, t)] = eout;
      const float* src = &in[Flat(0, y, t)];
      float* dst = &out[Flat(0, y, t)];
      std::copy(src + n - c, src + n, padded_row_.begin());
      std::copy(src, src + n, padded_row_.begin() + c);
      std::copy(src, src + c, padded_row_.begin() + c + n);
      for (auto [run_b, run_e] : xs_out.runs) {
        const int b = std::max(run_b, eout.lo), e = std::min(run_e, eout.hi);
        if (b < e) WeightedSum(dst, taps, w.data(), k_dim, b, e);
      }
    }
  }
}

void PoseCellNetwork::ConvolveY(const std::vector<float>& in, const RowFlags& in_rows,
                                std::vector<float>& out, RowFlags& out_rows,
                                const std::vector<float>& w, const AxisSet& /*xs*/,
                                const AxisSet& ys_in, const AxisSet& ys_out,
                                const AxisSet& ts) const {
  const int k_dim = static_cast<int>(w.size());
  const int c = k_dim / 2;
  const float* taps[kMaxTaps];
  float weights[kMaxTaps];
  for (int t : ts.index) {
    for (int y : ys_out.index) {
      RowExtent acc{dim_xy_, 0};
      int count = 0;
      for (int k = 0; k < k_dim; ++k) {
        const int ys = Wrap(y + k - c, dim_xy_);
        if (!ys_in.member[ys]) continue;
        const RowExtent ein = in_rows[Row(ys, t)];
        if (ein.empty()) continue;
        acc.lo = std::min(acc.lo, ein.lo);
        acc.hi = std::max(acc.hi, ein.hi);
        taps[count] = &in[Flat(0, ys, t)];
        weights[count++] = w[k];
      }
      out_rows[Row(y, t)] = acc.empty() ? RowExtent{} : acc;
      // Source rows are zero outside their extents: over the hull of the extents (widened to
      // whole vectors) the sum only adds zeros where a row has none.
      if (count > 0) {
        WeightedSum(&out[Flat(0, y, t)], taps, weights, count, acc.lo & ~3, std::min(dim_xy_, (acc.hi + 3) & ~3));
      }
    }
  }
}

void PoseCellNetwork::ConvolveTh(const std::vector<float>& in, const RowFlags& in_rows,
                                 std::vector<float>& out, RowFlags& out_rows,
                                 const std::vector<float>& w, const AxisSet& /*xs*/,
                                 const AxisSet& ys, const AxisSet& ts_in,
                                 const AxisSet& ts_out) const {
  const int k_dim = static_cast<int>(w.size());
  const int c = k_dim / 2;
  const float* taps[kMaxTaps];
  float weights[kMaxTaps];
  int layers[kMaxTaps];
  for (int t : ts_out.index) {
    int layer_count = 0;
    for (int k = 0; k < k_dim; ++k) {
      const int tsrc = Wrap(t + k - c, dim_th_);
      if (!ts_in.member[tsrc]) continue;
      layers[layer_count] = tsrc;
      weights[layer_count++] = w[k];
    }
    for (int y : ys.index) {
      RowExtent acc{dim_xy_, 0};
      int count = 0;
      float row_weights[kMaxTaps];
      for (int j = 0; j < layer_count; ++j) {
        const RowExtent ein = in_rows[Row(y, layers[j])];
        if (ein.empty()) continue;
        acc.lo = std::min(acc.lo, ein.lo);
        acc.hi = std::max(acc.hi, ein.hi);
        taps[count] = &in[Flat(0, y, layers[j])];
        row_weights[count++] = weights[j];
      }
      out_rows[Row(y, t)] = acc.empty() ? RowExtent{} : acc;
      if (count > 0) {
        WeightedSum(&out[Flat(0, y, t)], taps, row_weights, count, acc.lo & ~3,
                    std::min(dim_xy_, (acc.hi + 3) & ~3));
      }
    }
  }
}

// ---------------------------------------------------------------------------------------------
// Dynamics

void PoseCellNetwork::ExciteInhibitNormalise() {
  const int ce = config_.pc_w_e_dim / 2;
  Dilate(xs_, dim_xy_, ce, ce, ex_xs_);
  Dilate(ys_, dim_xy_, ce, ce, ex_ys_);
  Dilate(ts_, dim_th_, ce, ce, ex_ts_);

  // Excitation E = G_e * A, into buf_c_ over the dilated region.
  ConvolveX(activity_, rows_act_, buf_a_, rows_a_, excite_w_, ex_xs_, ys_, ts_);
  ConvolveY(buf_a_, rows_a_, buf_b_, rows_b_, excite_w_, ex_xs_, ys_, ex_ys_, ts_);
  ZeroRegion(buf_a_, ex_xs_, ys_, ts_);
  ConvolveTh(buf_b_, rows_b_, buf_c_, rows_c_, excite_w_, ex_xs_, ex_ys_, ts_, ex_ts_);
  ZeroRegion(buf_b_, ex_xs_, ex_ys_, ts_);

  // Inhibition I = G_i * E, needed only where E >= pc_global_inhib: elsewhere E - I - global
  // < 0, which the global inhibition clamps to zero (OpenRatSLAM zeroes anything below it).
  const float global = static_cast<float>(config_.pc_global_inhib);
  std::fill(tmp_xs_.member.begin(), tmp_xs_.member.end(), 0);
  std::fill(tmp_ys_.member.begin(), tmp_ys_.member.end(), 0);
  std::fill(tmp_ts_.member.begin(), tmp_ts_.member.end(), 0);
  for (int t : ex_ts_.index) {
    for (int y : ex_ys_.index) {
      if (rows_c_[Row(y, t)].empty()) continue;
      const float* e = &buf_c_[Flat(0, y, t)];
      uint8_t any = 0;  // branch-free: which cells pass is unpredictable
      for (auto [b, end] : ex_xs_.runs) any |= MarkStrong(e, tmp_xs_.member.data(), global, b, end);
      if (any) tmp_ys_.member[y] = tmp_ts_.member[t] = 1;
    }
  }
  tmp_xs_.Finish();
  tmp_ys_.Finish();
  tmp_ts_.Finish();
  ConvolveX(buf_c_, rows_c_, buf_a_, rows_a_, inhibit_w_, tmp_xs_, ex_ys_, ex_ts_);
  ConvolveY(buf_a_, rows_a_, buf_b_, rows_b_, inhibit_w_, tmp_xs_, ex_ys_, tmp_ys_, ex_ts_);
  ZeroRegion(buf_a_, tmp_xs_, ex_ys_, ex_ts_);
  ConvolveTh(buf_b_, rows_b_, buf_a_, rows_a_, inhibit_w_, tmp_xs_, tmp_ys_, ex_ts_, tmp_ts_);
  ZeroRegion(buf_b_, tmp_xs_, tmp_ys_, ex_ts_);

  // A = max(E - I - global, 0) over the strong region; everything else becomes zero.
  ZeroRegion(activity_, xs_, ys_, ts_);
  double total = 0.0;
  for (int t : tmp_ts_.index) {
    for (int y : tmp_ys_.index) {
      const size_t row = Flat(0, y, t);
      float* a = &activity_[row];
      const float* e = &buf_c_[row];
      float* inh = &buf_a_[row];
      if (rows_c_[Row(y, t)].empty()) {  // no excitation here: activity stays 0, clear the scratch
        for (auto [b, end] : tmp_xs_.runs) ZeroCells(inh, b, end);
        continue;
      }
      for (auto [b, end] : tmp_xs_.runs) ClampedDifference(e, inh, a, global, b, end);
      float row_total = 0.0f;  // in cell order, as the activity is normalised by it
      for (auto [b, end] : tmp_xs_.runs) {
        for (int x = b; x < end; ++x) row_total += a[x];
      }
      total += row_total;
    }
  }
  ZeroRegion(buf_c_, ex_xs_, ex_ys_, ex_ts_);
  std::swap(ex_xs_, tmp_xs_);  // the region RecomputeSupport scans below
  std::swap(ex_ys_, tmp_ys_);
  std::swap(ex_ts_, tmp_ts_);
  if (!(total > 0.0)) {
    // Cannot happen with valid parameters (the excitation peak always beats the inhibition);
    // recover deterministically rather than divide by zero.
    ZeroRegion(activity_, ex_xs_, ex_ys_, ex_ts_);
    RecomputeSupport(ex_xs_, ex_ys_, ex_ts_, nullptr);
    InjectEnergy(static_cast<int>(best_.x), static_cast<int>(best_.y), static_cast<int>(best_.th), 1.0);
    return;
  }
  // Activity is non-zero only where the excitation is (rows_c_ covers it).
  RecomputeSupport(ex_xs_, ex_ys_, ex_ts_, &rows_c_);
  const float scale = static_cast<float>(1.0 / total);
  for (int t : ts_.index) {
    for (int y : ys_.index) {
      if (rows_act_[Row(y, t)].empty()) continue;  // all zero: scaling changes nothing
      float* a = &activity_[Flat(0, y, t)];
      for (auto [b, e] : xs_.runs)
        for (int x = b; x < e; ++x) a[x] *= scale;
    }
  }
}

void PoseCellNetwork::PathIntegrate(double vtrans_mps, double vrot_radps, double dt_s) {
  if (!std::isfinite(vtrans_mps) || !std::isfinite(vrot_radps) || !std::isfinite(dt_s) || dt_s < 0) {
    throw std::invalid_argument("PathIntegrate: velocities and dt must be finite, dt >= 0");
  }
  const double shift_cells = vtrans_mps * dt_s / config_.pc_cell_x_size;
  const double cell_th = kTwoPi / dim_th_;
  if (shift_cells != 0.0) {
    // Each theta layer moves along its own direction; bilinear split of the fractional part
    // (OpenRatSLAM's weight_ne/nw/se/sw are this split for shifts under one cell).
    std::fill(tmp_xs_.member.begin(), tmp_xs_.member.end(), 0);
    std::fill(tmp_ys_.member.begin(), tmp_ys_.member.end(), 0);
    for (int t : ts_.index) {  // rows stay in their layer
      std::fill(rows_candidate_.begin() + Row(0, t), rows_candidate_.begin() + Row(0, t) + dim_xy_, RowExtent{});
    }
    for (int t : ts_.index) {
      const double dir = t * cell_th;
      const double sx = shift_cells * std::cos(dir);
      const double sy = shift_cells * std::sin(dir);
      const double fx_floor = std::floor(sx);
      const double fy_floor = std::floor(sy);
      const int ix = static_cast<int>(fx_floor);
      const int iy = static_cast<int>(fy_floor);
      const float fx = static_cast<float>(sx - fx_floor);
      const float fy = static_cast<float>(sy - fy_floor);
      const float w00 = (1 - fx) * (1 - fy), w10 = fx * (1 - fy), w01 = (1 - fx) * fy, w11 = fx * fy;
      for (int y : ys_.index) {
        const RowExtent source = rows_act_[Row(y, t)];
        if (source.empty()) continue;
        const float* src = &activity_[Flat(0, y, t)];
        const int y0 = Wrap(y + iy, dim_xy_);
        const int y1 = y0 + 1 == dim_xy_ ? 0 : y0 + 1;
        float* d0 = &buf_a_[Flat(0, y0, t)];
        float* d1 = &buf_a_[Flat(0, y1, t)];
        tmp_ys_.member[y0] = tmp_ys_.member[y1] = 1;
        // The non-zero cells of [lo, hi) land in [lo + ix, hi + ix + 1), wrapped (whole row
        // when that range wraps).
        const int start = Wrap(source.lo + ix, dim_xy_);
        const int stop = start + (source.hi - source.lo) + 1;
        const RowExtent moved = stop <= dim_xy_ ? RowExtent{start, stop} : RowExtent{0, dim_xy_};
        rows_candidate_[Row(y0, t)].Add(moved.lo, moved.hi);
        rows_candidate_[Row(y1, t)].Add(moved.lo, moved.hi);
        for (int x : xs_.index) {
          const float v = src[x];
          if (v == 0.0f) continue;
          const int x0 = Wrap(x + ix, dim_xy_);
          const int x1 = x0 + 1 == dim_xy_ ? 0 : x0 + 1;
          tmp_xs_.member[x0] = tmp_xs_.member[x1] = 1;
          d0[x0] += w00 * v;
          d0[x1] += w10 * v;
          d1[x0] += w01 * v;
          d1[x1] += w11 * v;
        }
      }
    }
    ZeroRegion(activity_, xs_, ys_, ts_);
    std::swap(activity_, buf_a_);
    tmp_xs_.Finish();
    tmp_ys_.Finish();
    tmp_ts_.member = ts_.member;
    tmp_ts_.Finish();
    RecomputeSupport(tmp_xs_, tmp_ys_, tmp_ts_, &rows_candidate_);
  }

  const double shift_th = vrot_radps * dt_s / cell_th;
  if (shift_th != 0.0) {
    const double floor_th = std::floor(shift_th);
    const int it = Wrap(static_cast<int>(std::fmod(floor_th, dim_th_)), dim_th_);
    const float f = static_cast<float>(shift_th - floor_th);
    std::fill(tmp_ts_.member.begin(), tmp_ts_.member.end(), 0);
    for (int t : ts_.index) {  // the layers rows move into, cleared before any is filled
      for (int layer : {Wrap(t + it, dim_th_), Wrap(t + it + 1, dim_th_)}) {
        std::fill(rows_candidate_.begin() + Row(0, layer), rows_candidate_.begin() + Row(0, layer) + dim_xy_,
                  RowExtent{});
      }
    }
    for (int t : ts_.index) {
      const int t0 = Wrap(t + it, dim_th_);
      const int t1 = t0 + 1 == dim_th_ ? 0 : t0 + 1;
      tmp_ts_.member[t0] = 1;
      if (f > 0.0f) tmp_ts_.member[t1] = 1;
      for (int y : ys_.index) {
        const RowExtent source = rows_act_[Row(y, t)];
        if (source.empty()) continue;
        rows_candidate_[Row(y, t0)].Add(source.lo, source.hi);  // rows keep their cells' x
        rows_candidate_[Row(y, t1)].Add(source.lo, source.hi);
        const float* src = &activity_[Flat(0, y, t)];
        float* d0 = &buf_a_[Flat(0, y, t0)];
        float* d1 = &buf_a_[Flat(0, y, t1)];
        const float keep = 1.0f - f;
        for (auto [b, e] : xs_.runs) {
          for (int x = b; x < e; ++x) {
            const float v = src[x];
            d0[x] += keep * v;
            d1[x] += f * v;
          }
        }
      }
    }
    ZeroRegion(activity_, xs_, ys_, ts_);
    std::swap(activity_, buf_a_);
    tmp_ts_.Finish();
    tmp_xs_.member = xs_.member;
    tmp_xs_.Finish();
    tmp_ys_.member = ys_.member;
    tmp_ys_.Finish();
    RecomputeSupport(tmp_xs_, tmp_ys_, tmp_ts_, &rows_candidate_);
  }
}

PoseCellPosition PoseCellNetwork::UpdateBestPose() {
  float best_v = -1.0f;
  int bx = 0, by = 0, bt = 0;
  for (int t : ts_.index) {
    for (int y : ys_.index) {
      // A row without activity cannot hold the peak (when no row has any, the pose is kept).
      if (rows_act_[Row(y, t)].empty()) continue;
      const float* row = &activity_[Flat(0, y, t)];
      for (int x : xs_.index) {
        if (row[x] > best_v) {
          best_v = row[x];
          bx = x;
          by = y;
          bt = t;
        }
      }
    }
  }
  if (best_v <= 0.0f) return best_;
  std::fill(avg_x_.begin(), avg_x_.end(), 0.0);
  std::fill(avg_y_.begin(), avg_y_.end(), 0.0);
  std::fill(avg_th_.begin(), avg_th_.end(), 0.0);
  const int a = config_.pc_cells_to_avg;
  for (int dt = -a; dt <= a; ++dt) {
    const int t = Wrap(bt + dt, dim_th_);
    for (int dy = -a; dy <= a; ++dy) {
      const int y = Wrap(by + dy, dim_xy_);
      const float* row = &activity_[Flat(0, y, t)];
      for (int dx = -a; dx <= a; ++dx) {
        const int x = Wrap(bx + dx, dim_xy_);
        const double v = row[x];
        avg_x_[x] += v;
        avg_y_[y] += v;
        avg_th_[t] += v;
      }
    }
  }
  // Population vector: circular mean of the cell indices, weighted by activity.
  auto circular_mean = [](const std::vector<double>& sums, int n) {
    double s = 0.0, c = 0.0;
    for (int i = 0; i < n; ++i) {
      if (sums[i] == 0.0) continue;
      const double ang = i * kTwoPi / n;
      s += sums[i] * std::sin(ang);
      c += sums[i] * std::cos(ang);
    }
    return WrapReal(std::atan2(s, c) * n / kTwoPi, n);
  };
  best_.x = circular_mean(avg_x_, dim_xy_);
  best_.y = circular_mean(avg_y_, dim_xy_);
  best_.th = circular_mean(avg_th_, dim_th_);
  return best_;
}

void PoseCellNetwork::Step(double vtrans_mps, double vrot_radps, double dt_s) {
  ValidateFrame(vtrans_mps, vrot_radps, dt_s, {});  // before anything changes
  ExciteInhibitNormalise();
  PathIntegrate(vtrans_mps, vrot_radps, dt_s);
  UpdateBestPose();
}

void PoseCellNetwork::InjectEnergy(int x, int y, int th, double energy) {
  if (!std::isfinite(energy) || energy < 0) {
    throw std::invalid_argument("pose cells: injected energy must be finite and >= 0");
  }
  x = Wrap(x, dim_xy_);
  y = Wrap(y, dim_xy_);
  th = Wrap(th, dim_th_);
  activity_[Flat(x, y, th)] += static_cast<float>(energy);
  RowExtent& row = rows_act_[Row(y, th)];
  row = row.empty() ? RowExtent{x, x + 1} : RowExtent{std::min(row.lo, x), std::max(row.hi, x + 1)};
  auto add = [](AxisSet& s, int i) {
    if (s.member[i]) return;
    s.member[i] = 1;
    s.Finish();
  };
  add(xs_, x);
  add(ys_, y);
  add(ts_, th);
}

// ---------------------------------------------------------------------------------------------
// Views and experiences

void PoseCellNetwork::ValidateFrame(double vtrans, double vrot, double dt, const ViewMatch& view) const {
  if (!std::isfinite(vtrans)) throw std::invalid_argument("pose cells: vtrans is not finite");
  if (!std::isfinite(vrot)) throw std::invalid_argument("pose cells: vrot is not finite");
  if (!std::isfinite(dt) || dt < 0) throw std::invalid_argument("pose cells: dt must be finite and >= 0");
  if (!std::isfinite(view.relative_angle_rad)) {
    throw std::invalid_argument("pose cells: view relative angle is not finite");
  }
  if (!std::isfinite(view.difference) || view.difference < 0) {
    throw std::invalid_argument("pose cells: view difference must be finite and >= 0");
  }
  if (view.template_id > views_.size()) {
    throw std::invalid_argument("pose cells: template id " + std::to_string(view.template_id) +
                                " skips ahead of the next expected id " + std::to_string(views_.size()));
  }
}

void PoseCellNetwork::InjectView(uint32_t template_id, double relative_angle_rad, bool is_new) {
  ValidateFrame(0.0, 0.0, 0.0, {template_id, is_new, relative_angle_rad});
  // is_new is advisory: a template is new exactly when its id is the next one.
  const double gamma_cells = relative_angle_rad / kTwoPi * dim_th_;
  const double active_decay = config_.vt_active_decay;
  if (template_id == views_.size()) {
    // 001 eq. 3: associate with the cell that would be active with no orientation offset.
    views_.push_back(
        {best_.x, best_.y, WrapReal(best_.th - gamma_cells, dim_th_), active_decay, view_updates_, {}});
  } else if (!views_[template_id].placed) {
    // Learnt while this network did not see it: this first sighting associates it (eq. 3).
    ViewAssociation& view = views_[template_id];
    view.pc_x = best_.x;
    view.pc_y = best_.y;
    view.pc_th = WrapReal(best_.th - gamma_cells, dim_th_);
    view.decay = active_decay;
    view.decay_stamp = view_updates_;
    view.placed = true;
  } else {
    ViewAssociation& view = views_[template_id];
    // Injection only from templates older than vt_inject_min_age (OpenRatSLAM: 10), so a view
    // just learnt here does not pull the packet back to where it already is.
    if (static_cast<uint64_t>(template_id) + config_.vt_inject_min_age < views_.size()) {
      double decay = EffectiveDecay(view);
      if (has_current_template_ && template_id == current_template_) decay += active_decay;
      view.decay = decay;
      view.decay_stamp = view_updates_;
      // OpenRatSLAM's decay curve: energy falls to zero after about three repeats.
      const double energy = config_.pc_vt_inject_energy * (30.0 - std::exp(1.2 * decay)) / 30.0;
      if (energy > 0.0) {
        view_delta_th_cells_ = gamma_cells;
        const double th = WrapReal(view.pc_th + gamma_cells, dim_th_);  // 001 eq. 4
        InjectEnergy(static_cast<int>(view.pc_x), static_cast<int>(view.pc_y),
                     static_cast<int>(th), energy);
      }
    }
  }
  ++view_updates_;  // every template's decay is restored by pc_vt_restore (lazily)
  previous_template_ = current_template_;
  has_previous_template_ = has_current_template_;
  current_template_ = template_id;
  has_current_template_ = true;
}

double PoseCellNetwork::EffectiveDecay(const ViewAssociation& v) const {
  const double restored = config_.pc_vt_restore * static_cast<double>(view_updates_ - v.decay_stamp);
  return std::max(config_.vt_active_decay, v.decay - restored);
}

double PoseCellNetwork::DeltaPc(const PoseCellPosition& p) const {
  const double th_corrected = WrapReal(best_.th - view_delta_th_cells_, dim_th_);
  const double dx = MinDelta(best_.x, p.x, dim_xy_);
  const double dy = MinDelta(best_.y, p.y, dim_xy_);
  const double dth = MinDelta(th_corrected, p.th, dim_th_);
  return std::sqrt(dx * dx + dy * dy + dth * dth);
}

bool PoseCellNetwork::Linked(uint32_t a, uint32_t b) const {
  const auto& la = links_of_[a];
  return std::find(la.begin(), la.end(), b) != la.end();
}

void PoseCellNetwork::CreateExperience(const FloorBoundary* boundary) {
  const uint32_t id = static_cast<uint32_t>(experiences_.size());
  experiences_.push_back({best_.x, best_.y, best_.th, current_template_, frames_processed_,
                          boundary ? std::optional(*boundary) : std::nullopt, odometry_});
  views_[current_template_].experience_ids.push_back(id);
  links_of_.emplace_back();
  if (has_current_experience_) {
    links_of_[current_experience_].push_back(id);
    links_of_[id].push_back(current_experience_);
  }
  current_experience_ = id;
  has_current_experience_ = true;
}

std::optional<BoundaryMatch> PoseCellNetwork::MatchBoundary(const ExperienceCell& e,
                                                            const FloorBoundary* boundary) const {
  const size_t min_points = static_cast<size_t>(config_.exp_boundary_min_points);
  if (!boundary || !e.boundary || boundary->size() < min_points || e.boundary->size() < min_points)
    return std::nullopt;
  return RegisterBoundaries(*e.boundary, *boundary);
}

std::optional<Eigen::Vector2d> PoseCellNetwork::ViewOffset(uint32_t recognised) const {
  const ExperienceCell& e = experiences_[recognised];
  if (!e.odometry) return std::nullopt;
  const RecentView* best = nullptr;
  const ExperienceCell* there = nullptr;  // where the robot stood at best
  const uint64_t max_gap = static_cast<uint64_t>(config_.exp_view_offset_max_gap_frames);
  for (auto it = recent_views_.rbegin(); it != recent_views_.rend(); ++it) {  // newest first: ties keep it
    if (best && it->difference >= best->difference) continue;
    const ExperienceCell* nearest = nullptr;
    uint64_t nearest_gap = max_gap + 1;
    for (uint32_t id : views_[it->template_id].experience_ids) {
      const ExperienceCell& c = experiences_[id];
      const uint64_t gap = c.created_frame > e.created_frame ? c.created_frame - e.created_frame
                                                             : e.created_frame - c.created_frame;
      if (c.odometry && gap < nearest_gap) {
        nearest_gap = gap;
        nearest = &c;
      }
    }
    if (!nearest) continue;
    best = &*it;
    there = nearest;
  }
  if (!best) return std::nullopt;
  const Pose2D offset = Compose(Between(*e.odometry, *there->odometry), Between(best->odometry, odometry_));
  return Eigen::Vector2d(offset.x, offset.y);
}

namespace {

// Appends the points, taken into another frame by `pose`, that fall in a 4-cm cell no point
// before them took: the walls of thirty frames overlap, and the registration's cost grows with
// the product of the two sides' points.
void AppendThinned(const Pose2D& pose, const FloorBoundary& points, std::unordered_set<uint64_t>& taken,
                   FloorBoundary& out) {
  constexpr double kCellM = 0.04;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  for (const Eigen::Vector2f& p : points) {
    const double x = pose.x + c * p.x() - s * p.y(), y = pose.y + s * p.x() + c * p.y();
    const auto cx = static_cast<uint32_t>(static_cast<int32_t>(std::floor(x / kCellM)));
    const auto cy = static_cast<uint32_t>(static_cast<int32_t>(std::floor(y / kCellM)));
    if (taken.insert(uint64_t{cx} << 32 | cy).second) out.emplace_back(static_cast<float>(x), static_cast<float>(y));
  }
}

}  // namespace

std::optional<BoundaryMatch> PoseCellNetwork::MatchSubmaps(uint32_t recognised) const {
  const ExperienceCell& e = experiences_[recognised];
  if (!e.odometry) return std::nullopt;
  const auto window = static_cast<uint64_t>(config_.exp_submap_frames);
  auto near = [&](const ExperienceCell& c) {
    return c.odometry && (c.created_frame > e.created_frame ? c.created_frame - e.created_frame
                                                            : e.created_frame - c.created_frame) <= window;
  };
  // Experiences are numbered in the order made: the visit's are those either side of it.
  uint32_t first = recognised, last = recognised;
  while (first > 0 && near(experiences_[first - 1])) --first;
  while (last + 1 < experiences_.size() && near(experiences_[last + 1])) ++last;
  FloorBoundary then, now;
  std::unordered_set<uint64_t> taken;
  for (uint32_t id = first; id <= last; ++id) {
    const ExperienceCell& c = experiences_[id];
    if (c.boundary) AppendThinned(Between(*e.odometry, *c.odometry), *c.boundary, taken, then);
  }
  taken.clear();
  for (const RecentBoundary& r : recent_boundaries_) AppendThinned(Between(odometry_, r.odometry), r.points, taken, now);
  const size_t min_points = static_cast<size_t>(config_.exp_boundary_min_points);
  if (then.size() < min_points || now.size() < min_points) return std::nullopt;
  return RegisterBoundaries(then, now);
}

void PoseCellNetwork::RememberBoundary(const FloorBoundary* boundary) {
  if (!config_.exp_submap_offset) return;
  if (boundary) recent_boundaries_.push_back({frames_processed_, odometry_, *boundary});
  while (!recent_boundaries_.empty() &&
         frames_processed_ - recent_boundaries_.front().frame > static_cast<uint64_t>(config_.exp_submap_frames))
    recent_boundaries_.pop_front();
}

bool PoseCellNetwork::BoundaryAligns(const BoundaryMatch& match) const {
  return match.median_residual_m < config_.exp_boundary_max_residual_m &&
         match.offset_m() < config_.exp_boundary_max_offset_m;
}

Action PoseCellNetwork::DecideAction(const FloorBoundary* boundary) {
  Action action;
  if (!has_current_template_) return action;
  action.template_id = current_template_;
  const uint32_t from = has_current_experience_ ? current_experience_ : kNoExperience;
  auto create = [&] {
    CreateExperience(boundary);
    action.kind = Action::Kind::kCreate;
    action.relative_angle_rad = 0.0;
  };
  if (!has_current_experience_) {
    create();
  } else {
    const ExperienceCell& cur = experiences_[current_experience_];
    const double delta_pc = DeltaPc({cur.pc_x, cur.pc_y, cur.pc_th});
    const ViewAssociation& view = views_[current_template_];
    const bool view_changed = !has_previous_template_ || previous_template_ != current_template_;
    if (view.experience_ids.empty()) {
      create();
    } else if (delta_pc > config_.exp_delta_pc_threshold || view_changed) {
      // The experience of this view closest in pose-cell space, other than the current one.
      double min_delta = std::numeric_limits<double>::max();
      uint32_t matched = kNoExperience;
      for (uint32_t id : view.experience_ids) {
        if (id == current_experience_) continue;
        const ExperienceCell& e = experiences_[id];
        const double d = DeltaPc({e.pc_x, e.pc_y, e.pc_th});
        if (d < min_delta) {
          min_delta = d;
          matched = id;
        }
      }
      // A view seen moments ago is not a recognition (exp_recognition_min_age_frames); an experience
      // adopted from the map (no odometry of this run) is old whatever its created_frame.
      const auto young = [&](uint32_t id) {
        const ExperienceCell& e = experiences_[id];
        return e.odometry && frames_processed_ - e.created_frame <
                                 static_cast<uint64_t>(config_.exp_recognition_min_age_frames);
      };
      const bool recognised =
          matched != kNoExperience && min_delta < config_.exp_delta_pc_threshold && !young(matched);
      const bool linked = recognised && Linked(current_experience_, matched);
      // A new link to an experience old enough is checked (exp_boundary_check): no measured
      // boundary, or one that does not align, refuses it. A boundary known only to one side
      // (adopted from the map, a frame without odometry) does not.
      const bool checked = recognised && !linked && config_.exp_boundary_check && boundary &&
                           experiences_[matched].boundary &&
                           frames_processed_ - experiences_[matched].created_frame >=
                               static_cast<uint64_t>(config_.exp_boundary_min_age_frames);
      std::optional<BoundaryMatch> match;
      if (checked || (recognised && config_.exp_boundary_offset)) match = MatchBoundary(experiences_[matched], boundary);
      const bool aligns = match && BoundaryAligns(*match);
      const bool boundary_refuses = checked && !aligns;
      // The walls of both visits (exp_submap_offset), and whether they refuse a new link; not
      // registered when the one frame's boundary already refused it.
      std::optional<BoundaryMatch> walls;
      if (recognised && !boundary_refuses && config_.exp_submap_offset &&
          frames_processed_ - experiences_[matched].created_frame >=
              static_cast<uint64_t>(config_.exp_submap_min_age_frames)) {
        walls = MatchSubmaps(matched);
      }
      const bool walls_align = walls && BoundaryAligns(*walls);
      const bool walls_refuse = config_.exp_submap_check && !linked && walls && !walls_align;
      if (!recognised) {
        create();
      } else if (boundary_refuses || walls_refuse) {
        create();
        action.refused_link_to = matched;
      } else {
        std::optional<Eigen::Vector2d> measured = config_.exp_view_offset ? ViewOffset(matched) : std::nullopt;
        if (walls_align) {
          std::optional<Eigen::Vector2d> guess = measured;
          if (!guess && aligns) guess = match->pose.head<2>();
          measured = guess && config_.exp_submap_alike_residual >= 1.0
                         ? walls->NearestAlike(*guess, config_.exp_submap_alike_residual)
                         : walls->pose.head<2>();
        }
        if (measured) {
          action.offset_x_m = measured->x();
          action.offset_y_m = measured->y();
        } else if (config_.exp_boundary_offset && aligns) {
          action.offset_x_m = match->pose.x();
          action.offset_y_m = match->pose.y();
        }
        if (linked) {
          action.kind = Action::Kind::kSet;
        } else {
          action.kind = Action::Kind::kLink;
          links_of_[current_experience_].push_back(matched);
          links_of_[matched].push_back(current_experience_);
        }
        current_experience_ = matched;
        action.relative_angle_rad = view_delta_th_cells_ * kTwoPi / dim_th_;
      }
    }
  }
  if (action.kind == Action::Kind::kNone) return action;
  action.from_experience_id = from;
  action.experience_id = current_experience_;
  const ExperienceCell& e = experiences_[current_experience_];
  action.pc_x = e.pc_x;
  action.pc_y = e.pc_y;
  action.pc_th = e.pc_th;
  action.sequence = next_sequence_++;
  return action;
}

Action PoseCellNetwork::ProcessFrame(double vtrans_mps, double vrot_radps, double dt_s, const ViewMatch& view,
                                     const FloorBoundary* boundary) {
  ValidateFrame(vtrans_mps, vrot_radps, dt_s, view);
  InjectView(view.template_id, view.relative_angle_rad, view.is_new);
  Step(vtrans_mps, vrot_radps, dt_s);
  DeadReckon(vtrans_mps * dt_s, vrot_radps * dt_s);
  if (config_.exp_view_offset) {
    recent_views_.push_back({view.template_id, view.difference, odometry_});
    if (recent_views_.size() > static_cast<size_t>(config_.exp_view_offset_frames)) recent_views_.pop_front();
  }
  ++frames_processed_;
  RememberBoundary(boundary);
  return DecideAction(boundary);
}

void PoseCellNetwork::SkipTemplates(uint32_t next_template_id) {
  if (next_template_id < views_.size()) {
    throw std::invalid_argument("pose cells: cannot skip back to template " + std::to_string(next_template_id) +
                                " (" + std::to_string(views_.size()) + " known)");
  }
  while (views_.size() < next_template_id) {
    views_.push_back({best_.x, best_.y, best_.th, config_.vt_active_decay, view_updates_, {}, false});
  }
}

Action PoseCellNetwork::ProcessFrameWithoutView(double vtrans_mps, double vrot_radps, double dt_s,
                                                const FloorBoundary* boundary) {
  ValidateFrame(vtrans_mps, vrot_radps, dt_s, {});
  Step(vtrans_mps, vrot_radps, dt_s);
  DeadReckon(vtrans_mps * dt_s, vrot_radps * dt_s);
  ++frames_processed_;
  RememberBoundary(boundary);
  // The view is unchanged: only the pose-cell distance can make a new experience.
  previous_template_ = current_template_;
  has_previous_template_ = has_current_template_;
  return DecideAction(boundary);
}

void PoseCellNetwork::DeadReckon(double distance_m, double turn_rad) {
  odometry_ = Compose(odometry_, {distance_m, 0.0, turn_rad});
}

void PoseCellNetwork::AdoptExperienceMap(const std::vector<MapExperience>& experiences,
                                         const std::vector<std::pair<uint32_t, uint32_t>>& links,
                                         uint32_t current_experience_id, bool move_packet) {
  auto fail = [](const std::string& why) { throw std::invalid_argument("pose cells: adopted map: " + why); };
  const uint32_t n = static_cast<uint32_t>(experiences.size());
  uint32_t template_end = static_cast<uint32_t>(views_.size());
  for (const MapExperience& e : experiences) {
    const PoseCellPosition& c = e.cell;
    if (!std::isfinite(c.x) || !std::isfinite(c.y) || !std::isfinite(c.th) || c.x < 0 || c.x >= dim_xy_ ||
        c.y < 0 || c.y >= dim_xy_ || c.th < 0 || c.th >= dim_th_) {
      fail("experience cell out of range");
    }
    if (e.template_id == kNoExperience) fail("template id out of range");
    template_end = std::max(template_end, e.template_id + 1);
  }
  for (const auto& [a, b] : links) {
    if (a >= n || b >= n) fail("link to unknown experience");
  }
  if (n > 0 && current_experience_id >= n) fail("current experience unknown");

  // Valid: commit. Associations for templates learnt while this network was down.
  std::vector<const PoseCellPosition*> first_cell(template_end, nullptr);
  for (const MapExperience& e : experiences) {
    if (!first_cell[e.template_id]) first_cell[e.template_id] = &e.cell;
  }
  const PoseCellPosition fallback = n > 0 ? experiences[current_experience_id].cell : best_;
  for (uint32_t t = static_cast<uint32_t>(views_.size()); t < template_end; ++t) {
    // A template without experiences is placed at its next sighting.
    const PoseCellPosition& p = first_cell[t] ? *first_cell[t] : fallback;
    views_.push_back({p.x, p.y, p.th, config_.vt_active_decay, view_updates_, {}, first_cell[t] != nullptr});
  }
  for (ViewAssociation& v : views_) v.experience_ids.clear();
  // An experience this network made itself (same id, template and cell) keeps what it knew of
  // it; the map's other experiences are unchecked by exp_boundary_check.
  std::vector<ExperienceCell> known = std::move(experiences_);
  experiences_.clear();
  for (uint32_t id = 0; id < n; ++id) {
    const MapExperience& e = experiences[id];
    if (id < known.size() && known[id].template_id == e.template_id &&
        std::abs(known[id].pc_x - e.cell.x) < 1e-3 && std::abs(known[id].pc_y - e.cell.y) < 1e-3 &&
        std::abs(known[id].pc_th - e.cell.th) < 1e-3) {
      experiences_.push_back(std::move(known[id]));
    } else {
      experiences_.push_back({e.cell.x, e.cell.y, e.cell.th, e.template_id, frames_processed_, std::nullopt, std::nullopt});
    }
    views_[e.template_id].experience_ids.push_back(id);
  }
  links_of_.assign(n, {});
  for (const auto& [a, b] : links) {
    if (a == b || Linked(a, b)) continue;
    links_of_[a].push_back(b);
    links_of_[b].push_back(a);
  }
  has_current_experience_ = n > 0;
  current_experience_ = n > 0 ? current_experience_id : 0;
  if (n == 0) return;
  const ExperienceCell& cur = experiences_[current_experience_];
  current_template_ = previous_template_ = cur.template_id;
  has_current_template_ = has_previous_template_ = true;
  view_delta_th_cells_ = 0.0;
  // The packet restarts where the robot last was, as the constructor starts it in the centre.
  if (move_packet) PlacePacket({cur.pc_x, cur.pc_y, cur.pc_th});
}

void PoseCellNetwork::PlacePacket(const PoseCellPosition& cell) {
  for (int t : ts_.index) {
    for (int y : ys_.index) rows_act_[Row(y, t)] = RowExtent{};
  }
  ZeroRegion(activity_, xs_, ys_, ts_);
  for (AxisSet* a : {&xs_, &ys_}) a->Reset(dim_xy_);
  ts_.Reset(dim_th_);
  const int x = Wrap(static_cast<int>(std::lround(cell.x)), dim_xy_);
  const int y = Wrap(static_cast<int>(std::lround(cell.y)), dim_xy_);
  const int th = Wrap(static_cast<int>(std::lround(cell.th)), dim_th_);
  InjectEnergy(x, y, th, 1.0);
  best_ = {static_cast<double>(x), static_cast<double>(y), static_cast<double>(th)};
}

bool PoseCellNetwork::RelocaliseToView(uint32_t template_id, double relative_angle_rad) {
  if (!std::isfinite(relative_angle_rad) || template_id >= views_.size()) return false;
  const ViewAssociation& view = views_[template_id];
  if (!view.placed || view.experience_ids.empty()) return false;
  const double gamma_cells = relative_angle_rad / kTwoPi * dim_th_;
  PlacePacket({view.pc_x, view.pc_y, WrapReal(view.pc_th + gamma_cells, dim_th_)});
  return true;
}

// ---------------------------------------------------------------------------------------------
// Access and persistence

float PoseCellNetwork::Activity(int x, int y, int th) const {
  if (x < 0 || x >= dim_xy_ || y < 0 || y >= dim_xy_ || th < 0 || th >= dim_th_) {
    throw std::out_of_range("pose cells: cell index out of range");
  }
  return activity_[Flat(x, y, th)];
}

double PoseCellNetwork::TotalActivity() const {
  double total = 0.0;
  for (int t : ts_.index)
    for (int y : ys_.index)
      for (int x : xs_.index) total += activity_[Flat(x, y, t)];
  return total;
}

int PoseCellNetwork::ActiveCellCount() const {
  int n = 0;
  for (int t : ts_.index)
    for (int y : ys_.index)
      for (int x : xs_.index) n += activity_[Flat(x, y, t)] != 0.0f;
  return n;
}

namespace {

// A floor boundary in the saved state: x0, y0, x1, y1, ... (experiences and recent boundaries).
void SavePoints(const FloorBoundary& points, google::protobuf::RepeatedField<float>* xy) {
  for (const Eigen::Vector2f& p : points) {
    xy->Add(p.x());
    xy->Add(p.y());
  }
}

bool ArePoints(const google::protobuf::RepeatedField<float>& xy) {
  return xy.size() % 2 == 0 && std::all_of(xy.begin(), xy.end(), [](float v) { return std::isfinite(v); });
}

FloorBoundary LoadPoints(const google::protobuf::RepeatedField<float>& xy) {
  FloorBoundary points;
  for (int i = 0; i + 1 < xy.size(); i += 2) points.emplace_back(xy[i], xy[i + 1]);
  return points;
}

}  // namespace

proto::State PoseCellNetwork::SaveState() const {
  proto::State s;
  s.set_dim_xy(dim_xy_);
  s.set_dim_th(dim_th_);
  for (int t : ts_.index) {
    for (int y : ys_.index) {
      for (int x : xs_.index) {
        const size_t i = Flat(x, y, t);
        if (activity_[i] != 0.0f) {
          s.add_active_index(static_cast<uint32_t>(i));
          s.add_active_value(activity_[i]);
        }
      }
    }
  }
  s.set_best_x(best_.x);
  s.set_best_y(best_.y);
  s.set_best_th(best_.th);
  for (const ViewAssociation& v : views_) {
    auto* pv = s.add_views();
    pv->set_pc_x(v.pc_x);
    pv->set_pc_y(v.pc_y);
    pv->set_pc_th(v.pc_th);
    pv->set_decay(v.decay);
    pv->set_decay_stamp(v.decay_stamp);
    pv->set_unplaced(!v.placed);
    for (uint32_t id : v.experience_ids) pv->add_experience_ids(id);
  }
  for (const ExperienceCell& e : experiences_) {
    auto* pe = s.add_experiences();
    pe->set_pc_x(e.pc_x);
    pe->set_pc_y(e.pc_y);
    pe->set_pc_th(e.pc_th);
    pe->set_template_id(e.template_id);
    pe->set_created_frame(e.created_frame);
    pe->set_boundary_known(e.boundary.has_value());
    if (e.boundary) SavePoints(*e.boundary, pe->mutable_boundary_xy());
    if (e.odometry) SavePose(*e.odometry, pe->mutable_odometry());
  }
  for (const RecentView& v : recent_views_) {
    auto* pv = s.add_recent_views();
    pv->set_template_id(v.template_id);
    pv->set_difference(v.difference);
    SavePose(v.odometry, pv->mutable_odometry());
  }
  for (const RecentBoundary& b : recent_boundaries_) {
    auto* pb = s.add_recent_boundaries();
    pb->set_frame(b.frame);
    SavePose(b.odometry, pb->mutable_odometry());
    SavePoints(b.points, pb->mutable_xy());
  }
  SavePose(odometry_, s.mutable_odometry());
  for (uint32_t a = 0; a < links_of_.size(); ++a) {
    for (uint32_t b : links_of_[a]) {
      if (a < b) {
        auto* pl = s.add_links();
        pl->set_from_experience_id(a);
        pl->set_to_experience_id(b);
      }
    }
  }
  s.set_has_current_experience(has_current_experience_);
  s.set_current_experience_id(current_experience_);
  s.set_has_current_template(has_current_template_);
  s.set_current_template_id(current_template_);
  s.set_has_previous_template(has_previous_template_);
  s.set_previous_template_id(previous_template_);
  s.set_view_delta_th_cells(view_delta_th_cells_);
  s.set_next_sequence(next_sequence_);
  s.set_frames_processed(frames_processed_);
  s.set_view_updates(view_updates_);
  return s;
}

void PoseCellNetwork::LoadState(const proto::State& s) {
  auto fail = [](const std::string& why) {
    throw std::invalid_argument("pose cells state: " + why);
  };
  if (static_cast<int>(s.dim_xy()) != dim_xy_ || static_cast<int>(s.dim_th()) != dim_th_) {
    fail("dimensions " + std::to_string(s.dim_xy()) + "x" + std::to_string(s.dim_th()) +
         " do not match the configured " + std::to_string(dim_xy_) + "x" + std::to_string(dim_th_));
  }
  if (s.active_index_size() != s.active_value_size()) fail("activity index/value counts differ");
  if (s.active_index_size() == 0) fail("no activity");
  const size_t cells = activity_.size();
  for (int i = 0; i < s.active_index_size(); ++i) {
    if (s.active_index(i) >= cells) fail("activity index out of range");
    const float v = s.active_value(i);
    if (!std::isfinite(v) || v < 0.0f) fail("activity value not finite or negative");
  }
  auto finite_pos = [&](double x, double y, double th) {
    return std::isfinite(x) && std::isfinite(y) && std::isfinite(th) && x >= 0 && x < dim_xy_ &&
           y >= 0 && y < dim_xy_ && th >= 0 && th < dim_th_;
  };
  if (!finite_pos(s.best_x(), s.best_y(), s.best_th())) fail("best pose out of range");
  const uint32_t n_views = s.views_size();
  const uint32_t n_exps = s.experiences_size();
  std::vector<int> seen_exp(n_exps, 0);
  for (const auto& v : s.views()) {
    if (!finite_pos(v.pc_x(), v.pc_y(), v.pc_th()) || !std::isfinite(v.decay()) ||
        v.decay_stamp() > s.view_updates()) {
      fail("view association out of range");
    }
    for (uint32_t id : v.experience_ids()) {
      if (id >= n_exps) fail("view refers to unknown experience " + std::to_string(id));
      ++seen_exp[id];
    }
  }
  for (uint32_t i = 0; i < n_exps; ++i) {
    const auto& e = s.experiences(i);
    if (!finite_pos(e.pc_x(), e.pc_y(), e.pc_th())) fail("experience cell out of range");
    if (e.template_id() >= n_views) fail("experience refers to unknown template");
    if (seen_exp[i] != 1) fail("experience not listed exactly once under its template");
    if (e.created_frame() > s.frames_processed()) fail("experience made after the last frame");
    if (!ArePoints(e.boundary_xy()) || (!e.boundary_known() && e.boundary_xy_size() > 0))
      fail("experience boundary is not a list of finite points");
    if (!IsFinite(LoadPose(e.odometry()))) fail("experience odometry pose not finite");
  }
  for (const auto& v : s.recent_views()) {
    if (v.template_id() >= n_views) fail("recent view refers to unknown template");
    if (!std::isfinite(v.difference()) || v.difference() < 0 || !IsFinite(LoadPose(v.odometry())))
      fail("recent view not finite");
  }
  for (const auto& b : s.recent_boundaries()) {
    if (b.frame() > s.frames_processed()) fail("recent boundary seen after the last frame");
    if (!ArePoints(b.xy())) fail("recent boundary is not a list of finite points");
    if (!IsFinite(LoadPose(b.odometry()))) fail("recent boundary odometry pose not finite");
  }
  if (!IsFinite(LoadPose(s.odometry()))) fail("odometry pose not finite");
  for (const auto& l : s.links()) {
    if (l.from_experience_id() >= n_exps || l.to_experience_id() >= n_exps) fail("link to unknown experience");
  }
  if (s.has_current_experience() && s.current_experience_id() >= n_exps) fail("current experience unknown");
  if (s.has_current_experience() != (n_exps > 0)) fail("current experience flag inconsistent");
  if (s.has_current_template() && s.current_template_id() >= n_views) fail("current template unknown");
  if (s.has_previous_template() && s.previous_template_id() >= n_views) fail("previous template unknown");
  if (!std::isfinite(s.view_delta_th_cells())) fail("view offset not finite");

  // Valid: commit.
  ZeroRegion(activity_, xs_, ys_, ts_);
  for (AxisSet* a : {&xs_, &ys_}) a->Reset(dim_xy_);
  ts_.Reset(dim_th_);
  for (int i = 0; i < s.active_index_size(); ++i) {
    const uint32_t idx = s.active_index(i);
    const int x = static_cast<int>(idx % dim_xy_);
    const int y = static_cast<int>((idx / dim_xy_) % dim_xy_);
    const int t = static_cast<int>(idx / (static_cast<uint32_t>(dim_xy_) * dim_xy_));
    activity_[idx] = 0.0f;
    InjectEnergy(x, y, t, s.active_value(i));
  }
  best_ = {s.best_x(), s.best_y(), s.best_th()};
  views_.clear();
  for (const auto& v : s.views()) {
    views_.push_back({v.pc_x(), v.pc_y(), v.pc_th(), v.decay(), v.decay_stamp(),
                      std::vector<uint32_t>(v.experience_ids().begin(), v.experience_ids().end()), !v.unplaced()});
  }
  experiences_.clear();
  for (const auto& e : s.experiences()) {
    std::optional<FloorBoundary> boundary;
    if (e.boundary_known()) boundary = LoadPoints(e.boundary_xy());
    experiences_.push_back({e.pc_x(), e.pc_y(), e.pc_th(), e.template_id(), e.created_frame(), std::move(boundary),
                            e.has_odometry() ? std::optional(LoadPose(e.odometry())) : std::nullopt});
  }
  recent_views_.clear();
  for (const auto& v : s.recent_views()) recent_views_.push_back({v.template_id(), v.difference(), LoadPose(v.odometry())});
  while (recent_views_.size() > static_cast<size_t>(config_.exp_view_offset_frames)) recent_views_.pop_front();
  recent_boundaries_.clear();
  for (const auto& b : s.recent_boundaries())
    recent_boundaries_.push_back({b.frame(), LoadPose(b.odometry()), LoadPoints(b.xy())});
  odometry_ = LoadPose(s.odometry());
  links_of_.assign(n_exps, {});
  for (const auto& l : s.links()) {
    links_of_[l.from_experience_id()].push_back(l.to_experience_id());
    links_of_[l.to_experience_id()].push_back(l.from_experience_id());
  }
  has_current_experience_ = s.has_current_experience();
  current_experience_ = s.current_experience_id();
  has_current_template_ = s.has_current_template();
  current_template_ = s.current_template_id();
  has_previous_template_ = s.has_previous_template();
  previous_template_ = s.previous_template_id();
  view_delta_th_cells_ = s.view_delta_th_cells();
  next_sequence_ = s.next_sequence();
  frames_processed_ = s.frames_processed();
  view_updates_ = s.view_updates();
}

}  // namespace rslam::pose_cells
