// The velocity field of Eq. 2–7 (DESIGN.md §1) for TW_VECS×16 points per work-item, in explicit 16-lane vectors
// (PoCL 3.1 does not vectorise across work-items when a kernel has inner loops). Same field as the CPU
// reference (core/src/velocity_field.cpp), normalised so that every weight is finite and ≤ 1 near features.
//
// The host's prelude (kernels/src/kernel_contract.hpp) defines every TW_ constant used here, and TW_DOUBLE for
// double instead of float arithmetic.
//
// Weights. With a_i = d_i^−α (positional), b_g = d_g^−α (gradient), pairs weigh a_i·a_j (ordered, so twice per
// unordered pair) and gradient features b_g; only ratios matter. Distances are in units of
// WarpProblem::weight_length_px = L, as in the CPU field. Per point, with r = d² (pixels²) and h = α/2:
//   z_j = (r_(2) / r_j)^h = a_j / a_(2)    r_(1) ≤ r_(2): the two nearest positional features; z ≤ TW_ZMAX
//   μ   = 1 / z_(1)                         so that μ·z_i·z_j = a_i·a_j / (a_(1)·a_(2)) ≤ 1
//   X   = b_max / (a_(1)·a_(2)),  ln X = h·(ln r_(1) + ln r_(2) − ln r_gmin − ln L²),
//   γ   = min(1, 1/X),  γ' = min(1, X)
//   pair weight 2·γ·μ·z_i·z_j, gradient weight γ'·b_g / b_max:
// the exact weights divided by the largest one, so the largest is 1 and nothing is 0/0. At a positional
// feature z_(1) = ∞ is clamped: the pairs through it keep their exact relative weights, the other pairs fall to
// ≤ 1/TW_ZMAX relative weight (their exact weight is 0 there); the field is then the feature's velocity.
//
// Pair sum. v_ij(p) = D_i + (p − F_i)·c_ij (Eq. 3), c_ij = c_ji. For row i, Σ_{j>i} z_j·v_ij(p) =
// D_i·S_i + δ_i·R_i with S_i = Σ_{j>i} z_j, R_i = Σ_{j>i} z_j·c_ij, δ_i = p − F_i: the O(n²) hot loop is R_i alone,
// two FMAs per unordered pair per 16 points, with c_ij(t) computed once per stage for the work-item's 64 points.
// The loop runs over columns in blocks of TW_COLUMN_BLOCK so that the z it streams stay in the L1 cache.
//
// Coordinates. Each point carries its own origin o (a float close to its start position) and an offset p' from
// it; feature positions come as hi + lo parts. δ = (o − F_hi) + (p' − (F_lo + t·D)) keeps relative precision
// for coordinates up to 2^24 px even when p and F are far from the image origin.
//
// Gradient (field_evaluate_gradient, for the variational equation of the pathlines): see that function.

#ifdef TW_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double real;
typedef double16 real16;
typedef long16 mask16;
#else
typedef float real;
typedef float16 real16;
typedef int16 mask16;
#endif

// TW_VECS 16-lane vectors per work-item, written out by TW_EACH_VEC: PoCL's compiler does not unroll even short
// constant loops, and arrays indexed in a loop would stay in memory instead of registers.
#if TW_VECS != 4 || TW_LANES != 16
#error "the kernels are written for TW_VECS == 4 vectors of TW_LANES == 16 lanes (real16)"
#endif
#define TW_EACH_VEC(...)         \
  {                              \
    const int v = 0;             \
    __VA_ARGS__                  \
  }                              \
  {                              \
    const int v = 1;             \
    __VA_ARGS__                  \
  }                              \
  {                              \
    const int v = 2;             \
    __VA_ARGS__                  \
  }                              \
  {                              \
    const int v = 3;             \
    __VA_ARGS__                  \
  }

// q^h for h = α/2 in the mode TW_POW_* the host chose for α.
inline real16 pow_half_alpha(real16 q, int mode, real h) {
  switch (mode) {
    case TW_POW_ALPHA2: return q;
    case TW_POW_ALPHA3: return q * sqrt(q);
    case TW_POW_ALPHA1_5: return sqrt(q * sqrt(q));
    case TW_POW_ALPHA1: return sqrt(q);
    case TW_POW_ALPHA4: return q * q;
    case TW_POW_GENERAL:
    default: return pow(q, (real16)(h));
  }
}

// A gradient feature's weight at squared distance r: γ'·(r_gmin / r)^h (γ' for the nearest, at r = r_gmin),
// relative like every weight here (see the header).
inline real16 gradient_weight(real16 r, real16 rg_min, real16 scale, int mode, real h) {
  const real16 q = select(rg_min / r, (real16)(1), (mask16)(r <= rg_min));
  return scale * pow_half_alpha(q, mode, h);
}

// Where a work-item's scratch arrays lie (offsets in reals from its slot; z is 16-real aligned).
typedef struct {
  int n;                 // positional features
  int m;                 // gradient features
  int pairs16;           // n(n−1)/2 rounded up to a multiple of 16
  int pow_mode;          // TW_POW_*
  real half_alpha;       // h = α/2
  real log_inv_length2;  // ln(1 / L²), L = the weights' length unit in pixels
} FieldShape;

// Where the unordered pair (i, j), i < j, lies in the packed pair arrays (row i starts at i·n − i(i+1)/2): scalar
// or int16 operands.
#define TW_PAIR_SLOT(i, j, n) ((i) * (n) - ((i) * ((i) + 1)) / 2 + (j) - (i) - 1)

// The part of the field that depends on t only, for one work-item: c_ij(t) for every unordered pair (16 pairs
// per vector operation) and F_lo + t·D for every feature. Pair records: SoA of ΔF(0) = F_j(0) − F_i(0) and
// ΔD = D_j − D_i, so ΔF(t) = ΔF(0) + t·ΔD and c_ij = ΔD / ΔF(t) (Eq. 2, complex division).
void field_coefficients(real t, FieldShape s, __global const real* feat, __global const real* grad,
                        __global const real* pairs, __global real* cx, __global real* cy, __global real* flo,
                        __global real* glo) {
  __global const real* f0x = pairs + TW_PAIR_F0_X * s.pairs16;
  __global const real* f0y = pairs + TW_PAIR_F0_Y * s.pairs16;
  __global const real* ddx = pairs + TW_PAIR_DD_X * s.pairs16;
  __global const real* ddy = pairs + TW_PAIR_DD_Y * s.pairs16;
  const real16 tv = (real16)(t);
  for (int q = 0; q < s.pairs16; q += TW_LANES) {
    const real16 ax = vload16(0, ddx + q);
    const real16 ay = vload16(0, ddy + q);
    const real16 fx = fma(tv, ax, vload16(0, f0x + q));
    const real16 fy = fma(tv, ay, vload16(0, f0y + q));
    const real16 inv = (real16)(1) / fma(fx, fx, fy * fy);
    vstore16(fma(ax, fx, ay * fy) * inv, 0, cx + q);
    vstore16(fma(ay, fx, -(ax * fy)) * inv, 0, cy + q);
  }
  for (int i = 0; i < s.n; ++i) {
    __global const real* f = feat + TW_POS_STRIDE * i;
    flo[2 * i] = fma(t, f[TW_REC_D_X], f[TW_REC_LO_X]);
    flo[2 * i + 1] = fma(t, f[TW_REC_D_Y], f[TW_REC_LO_Y]);
  }
  for (int g = 0; g < s.m; ++g) {
    __global const real* f = grad + TW_GRAD_STRIDE * g;
    glo[2 * g] = fma(t, f[TW_REC_D_X], f[TW_REC_LO_X]);
    glo[2 * g + 1] = fma(t, f[TW_REC_D_Y], f[TW_REC_LO_Y]);
  }
}

// The offset δ = p − F(t) of a point (origin o, offset p') from a feature (F_hi, F_lo + t·D): see the header.
inline real16 feature_offset(real16 o, real16 p, real f_hi, real f_lo) { return (o - f_hi) + (p - f_lo); }

// The common prologue of field_evaluate and field_evaluate_gradient: the normalisers of the weights (see the
// header) for the work-item's TW_VECS×TW_LANES points. Out: rg_min (nearest gradient feature's r, ∞ when m = 0),
// and when n > 0 the two nearest positional features' r1 ≤ r2, z1 = (r2 / r1)^h clamped at TW_ZMAX, pair_scale
// 2·γ·μ; grad_scale γ' (1 when n = 0); every positional feature's r_i at r_col[i·col_stride + v]. With `nearest`
// (a constant at each call: the code for it goes when it is false), also the nearest feature of either kind: its
// offset (kdx, kdy), velocity (kux, kuy) and r (kr); without it these are not touched.
inline __attribute__((always_inline)) void field_normalisers(
    FieldShape s, __global const real* feat, __global const real* grad, __global const real* flo,
    __global const real* glo, const real16* ox, const real16* oy, const real16* px, const real16* py,
    __global real16* r_col, const int col_stride, const bool nearest, real16* rg_min, real16* r1, real16* r2,
    real16* z1, real16* pair_scale, real16* grad_scale, real16* kdx, real16* kdy, real16* kux, real16* kuy,
    real16* kr) {
  const int mode = s.pow_mode;
  const real h = s.half_alpha;
  TW_EACH_VEC(
    rg_min[v] = (real16)(INFINITY);
    grad_scale[v] = (real16)(1);
  );
  if (nearest) {
    TW_EACH_VEC(kdx[v] = kdy[v] = kux[v] = kuy[v] = (real16)(0);)
  }
  // Nearest gradient feature (squared distance). min/max rather than fmin/fmax in the O(n) passes: one
  // instruction instead of four (fmin's NaN rules); the values are ≥ 0 or +∞, a NaN input fails later anyway.
  for (int g = 0; g < s.m; ++g) {
    __global const real* f = grad + TW_GRAD_STRIDE * g;
    const real fx = f[TW_REC_HI_X], fy = f[TW_REC_HI_Y], lx = glo[2 * g], ly = glo[2 * g + 1];
    const real ux = f[TW_REC_D_X], uy = f[TW_REC_D_Y];
    TW_EACH_VEC(
      const real16 dx = feature_offset(ox[v], px[v], fx, lx);
      const real16 dy = feature_offset(oy[v], py[v], fy, ly);
      const real16 r = fma(dx, dx, dy * dy);
      if (nearest) {
        const mask16 closer = (mask16)(r < rg_min[v]);
        kdx[v] = select(kdx[v], dx, closer);
        kdy[v] = select(kdy[v], dy, closer);
        kux[v] = select(kux[v], (real16)(ux), closer);
        kuy[v] = select(kuy[v], (real16)(uy), closer);
      }
      rg_min[v] = min(rg_min[v], r);
    );
  }
  if (nearest) {
    TW_EACH_VEC(kr[v] = rg_min[v];)
  }
  if (s.n == 0) return;

  // Squared distances into the columns, the two nearest positional features (and the nearest feature).
  TW_EACH_VEC(r1[v] = r2[v] = (real16)(INFINITY);)
  for (int i = 0; i < s.n; ++i) {
    __global const real* f = feat + TW_POS_STRIDE * i;
    const real fx = f[TW_REC_HI_X], fy = f[TW_REC_HI_Y], lx = flo[2 * i], ly = flo[2 * i + 1];
    const real ux = f[TW_REC_D_X], uy = f[TW_REC_D_Y];
    TW_EACH_VEC(
      const real16 dx = feature_offset(ox[v], px[v], fx, lx);
      const real16 dy = feature_offset(oy[v], py[v], fy, ly);
      const real16 r = fma(dx, dx, dy * dy);
      r_col[i * col_stride + v] = r;
      r2[v] = min(r2[v], max(r1[v], r));
      r1[v] = min(r1[v], r);
      if (nearest) {
        const mask16 closer = (mask16)(r < kr[v]);
        kr[v] = select(kr[v], r, closer);
        kdx[v] = select(kdx[v], dx, closer);
        kdy[v] = select(kdy[v], dy, closer);
        kux[v] = select(kux[v], (real16)(ux), closer);
        kuy[v] = select(kuy[v], (real16)(uy), closer);
      }
    );
  }
  TW_EACH_VEC(
    z1[v] = min(pow_half_alpha(r2[v] / r1[v], mode, h), (real16)(TW_ZMAX));
    if (s.m == 0) {  // no gradient feature: γ = 1, no logarithms
      pair_scale[v] = (real16)(2) / z1[v];
    } else {
      const real16 ln_x = (real16)(h) * (log(r1[v]) + log(r2[v]) - log(rg_min[v]) + (real16)(s.log_inv_length2));
      pair_scale[v] = (real16)(2) * exp(fmin((real16)(0), -ln_x)) / z1[v];
      grad_scale[v] = exp(fmin((real16)(0), ln_x));
    }
  );
}

// The hot loop of field_evaluate: row i's sum R_i = Σ_j z_j·c_ij (rx, ry) over its columns from rcx to row_end,
// for the TW_PAIR_PASS vectors from v0, two columns per trip. A core starts two FMAs per cycle and has an FMA's
// result four cycles later: a sum that takes both columns of a trip (a chain of two FMAs per trip) held the loop
// to half the FMA rate (41 % of the nominal peak at n = 200, measured with texwarp_bench_kernels). Each sum is
// therefore kept as two partial sums, the even and the odd columns', added at the row's end: 4·TW_PAIR_PASS chains
// of one FMA per trip. Float: all four vectors in one pass (16 sums, 16 FMAs against 4 broadcasts and 8 loads per
// trip, in AVX-512's 32 registers: PoCL's code for this CPU is 512-bit, a float16 one register), so the row's
// coefficients are read once. Double: one vector per pass (a double16 is two registers: its 4 partial sums take 8).
#ifdef TW_DOUBLE
#define TW_PAIR_PASS 1
#else
#define TW_PAIR_PASS 4
#endif

// pair_row_sums' steps for vector v0 + k of the pass: its four partial sums, a trip's two columns, the last odd
// column, and the sums added into rx, ry.
#define TW_PAIR_SUMS_OF(k)                          \
  real16 xe##k = (real16)(0), ye##k = (real16)(0); \
  real16 xo##k = (real16)(0), yo##k = (real16)(0);
#define TW_PAIR_TRIP_OF(k)                                     \
  {                                                            \
    const real16 ze = zp[v0 + k], zo = zp[TW_VECS + v0 + k]; \
    xe##k = fma(ze, a0, xe##k);                                \
    ye##k = fma(ze, b0, ye##k);                                \
    xo##k = fma(zo, a1, xo##k);                                \
    yo##k = fma(zo, b1, yo##k);                                \
  }
#define TW_PAIR_LAST_OF(k)        \
  {                               \
    const real16 ze = zp[v0 + k]; \
    xe##k = fma(ze, a0, xe##k);   \
    ye##k = fma(ze, b0, ye##k);   \
  }
#define TW_PAIR_ADD_OF(k)        \
  rx[v0 + k] += xe##k + xo##k; \
  ry[v0 + k] += ye##k + yo##k;
#if TW_PAIR_PASS == 1
#define TW_PAIR_EACH(M) M(0)
#elif TW_PAIR_PASS == 4
#define TW_PAIR_EACH(M) M(0) M(1) M(2) M(3)
#else
#error "TW_PAIR_PASS must be 1 or 4"
#endif

// Pointers advance instead of indices (fewer integer operations).
inline void pair_row_sums(__global const real* rcx, __global const real* rcy, __global const real* row_end,
                          __global const real16* zp, const int v0, real16* rx, real16* ry) {
  TW_PAIR_EACH(TW_PAIR_SUMS_OF)
  for (; rcx + 1 < row_end; rcx += 2, rcy += 2, zp += 2 * TW_VECS) {
    const real16 a0 = (real16)(rcx[0]), b0 = (real16)(rcy[0]);
    const real16 a1 = (real16)(rcx[1]), b1 = (real16)(rcy[1]);
    TW_PAIR_EACH(TW_PAIR_TRIP_OF)
  }
  if (rcx < row_end) {
    const real16 a0 = (real16)(rcx[0]), b0 = (real16)(rcy[0]);
    TW_PAIR_EACH(TW_PAIR_LAST_OF)
  }
  TW_PAIR_EACH(TW_PAIR_ADD_OF)
}

// v(p, t) for the work-item's TW_VECS×TW_LANES points: origins (ox, oy), offsets (px, py); coefficients from
// field_coefficients at the same t. z: scratch of n·TW_VECS vectors; acc: of TW_ROW_SUMS·n·TW_VECS vectors when
// n > TW_COLUMN_BLOCK. Pixels per unit time.
void field_evaluate(FieldShape s, __global const real* feat, __global const real* grad,
                    __global const real* cx, __global const real* cy, __global const real* flo,
                    __global const real* glo, __global real16* z, __global real16* acc, const real16* ox, const real16* oy,
                    const real16* px, const real16* py, real16* vx, real16* vy) {
  const int mode = s.pow_mode;
  const real h = s.half_alpha;
  real16 rg_min[TW_VECS], r1[TW_VECS], r2[TW_VECS], z1[TW_VECS], pair_scale[TW_VECS], grad_scale[TW_VECS];
  real16 none[TW_VECS];  // field_normalisers' nearest feature, not asked for
  field_normalisers(s, feat, grad, flo, glo, ox, oy, px, py, z, TW_VECS, false, rg_min, r1, r2, z1, pair_scale,
                    grad_scale, none, none, none, none, none);
  real16 num_x[TW_VECS], num_y[TW_VECS], den[TW_VECS];
  TW_EACH_VEC(num_x[v] = num_y[v] = den[v] = (real16)(0);)

  if (s.n > 0) {
    for (int i = 0; i < s.n; ++i) {
      TW_EACH_VEC(
        z[i * TW_VECS + v] = min(pow_half_alpha(r2[v] / z[i * TW_VECS + v], mode, h), (real16)(TW_ZMAX));
      );
    }
    // Rows from the last, so that S_i = Σ_{j>i} z_j grows by one term per row; columns in blocks of
    // TW_COLUMN_BLOCK features, also from the last, so that the z of a block stay in the L1 cache while every
    // row runs over them. A row whose columns continue in an earlier-visited block keeps its partial R_i in
    // `acc` (used only when n > TW_COLUMN_BLOCK).
    real16 row_sum[TW_VECS];
    TW_EACH_VEC(row_sum[v] = (real16)(0);)
    for (int j0 = (s.n - 1) / TW_COLUMN_BLOCK * TW_COLUMN_BLOCK; j0 >= 0; j0 -= TW_COLUMN_BLOCK) {
      const int j1 = min(j0 + TW_COLUMN_BLOCK, s.n);
      for (int i = j1 - 2; i >= 0; --i) {
        const bool complete = i + 1 >= j0;  // no column of row i lies in a block still to come
        real16 rx[TW_VECS], ry[TW_VECS];
        __global real16* row_acc = acc + TW_ROW_SUMS * TW_VECS * i;
        if (j1 < s.n) {
          TW_EACH_VEC(
            rx[v] = row_acc[v];
            ry[v] = row_acc[TW_VECS + v];
          );
        } else {
          TW_EACH_VEC(rx[v] = ry[v] = (real16)(0);)
        }
        // Row i of the packed pairs (it starts at i·n − i(i+1)/2) against z_j over the block's columns j > i.
        const int first = complete ? i + 1 : j0;
        const int row = TW_PAIR_SLOT(i, 0, s.n);
        TW_EACH_VEC(  // one pass from every TW_PAIR_PASS-th vector (v is a constant: the test folds away)
          if (v % TW_PAIR_PASS == 0) {
            pair_row_sums(cx + row + first, cy + row + first, cx + row + j1, z + first * TW_VECS, v, rx, ry);
          }
        );
        if (!complete) {
          TW_EACH_VEC(
            row_acc[v] = rx[v];
            row_acc[TW_VECS + v] = ry[v];
          );
          continue;
        }
        __global const real* f = feat + TW_POS_STRIDE * i;
        const real fx = f[TW_REC_HI_X], fy = f[TW_REC_HI_Y], lx = flo[2 * i], ly = flo[2 * i + 1];
        const real ux = f[TW_REC_D_X], uy = f[TW_REC_D_Y];
        TW_EACH_VEC(
          row_sum[v] += z[(i + 1) * TW_VECS + v];
          const real16 dx = feature_offset(ox[v], px[v], fx, lx);
          const real16 dy = feature_offset(oy[v], py[v], fy, ly);
          const real16 wx = fma((real16)(ux), row_sum[v], fma(dx, rx[v], -(dy * ry[v])));
          const real16 wy = fma((real16)(uy), row_sum[v], fma(dx, ry[v], dy * rx[v]));
          const real16 zi = z[i * TW_VECS + v];
          num_x[v] = fma(zi, wx, num_x[v]);
          num_y[v] = fma(zi, wy, num_y[v]);
          den[v] = fma(zi, row_sum[v], den[v]);
        );
      }
    }
    TW_EACH_VEC(
      num_x[v] *= pair_scale[v];
      num_y[v] *= pair_scale[v];
      den[v] *= pair_scale[v];
    );
  }

  // Gradient features (Eq. 4): v_g(p) = D_g + κ_g·(p − F_g), weight γ'·(r_min / r_g)^h (1 for the nearest).
  for (int g = 0; g < s.m; ++g) {
    __global const real* f = grad + TW_GRAD_STRIDE * g;
    const real fx = f[TW_REC_HI_X], fy = f[TW_REC_HI_Y], lx = glo[2 * g], ly = glo[2 * g + 1];
    const real ux = f[TW_REC_D_X], uy = f[TW_REC_D_Y], kx = f[TW_REC_KAPPA_X], ky = f[TW_REC_KAPPA_Y];
    TW_EACH_VEC(
      const real16 dx = feature_offset(ox[v], px[v], fx, lx);
      const real16 dy = feature_offset(oy[v], py[v], fy, ly);
      const real16 r = fma(dx, dx, dy * dy);
      const real16 w = gradient_weight(r, rg_min[v], grad_scale[v], mode, h);
      num_x[v] = fma(w, fma((real16)(kx), dx, fma((real16)(-ky), dy, (real16)(ux))), num_x[v]);
      num_y[v] = fma(w, fma((real16)(kx), dy, fma((real16)(ky), dx, (real16)(uy))), num_y[v]);
      den[v] += w;
    );
  }

  TW_EACH_VEC(
    vx[v] = num_x[v] / den[v];
    vy[v] = num_y[v] / den[v];
  );
}

// field_evaluate_gradient's columns, TW_VECS vectors per feature each, in four arrays: z°_j (z_j, 0 for the
// nearest positional feature p of the lane), z°_j·g_j.x, z°_j·g_j.y and the factor f_j of g_j = ∇ln z_j = f_j·δ_j.
#if TW_GRADIENT_ARRAYS != 4
#error "field_evaluate_gradient's scratch holds four arrays per feature: z°, z°·g.x, z°·g.y, f"
#endif
#define TW_GRADIENT_ARRAY(col, k, n) ((col) + (k) * (n) * TW_VECS)

// The factor f of ∇ln w = f·δ for a weight w = d^−α at offset δ from its feature, r = |δ|², inv_r = 1 / r:
// f = −α / r, pixels⁻². 0 where the computed weight does not vary with p: `flat` (its z was clamped at TW_ZMAX) or
// r < TW_R_FLAT (at the feature itself, and where −α / r would overflow).
inline real16 log_weight_factor(real16 r, real16 inv_r, mask16 flat, real alpha) {
  return select((real16)(-alpha) * inv_r, (real16)(0), flat | (mask16)(r < (real16)(TW_R_FLAT)));
}

// The pair loop's column-wise half for field_evaluate_gradient's full rows: row i's sum over the columns j of
// [j, j + count) below it, Σ z°_j·c_ji, whose pairs (j, i) lie in the packed rows j at p, p + step, p + 2·step − 1,
// … (a packed row is one shorter than the one before); zp at z°_j. Two columns per trip with even and odd partial
// sums, as pair_row_sums.
inline void pair_column_sums(__global const real* cx, __global const real* cy, int p, int step, int count,
                             __global const real16* zp, const int v0, real16* rx, real16* ry) {
  TW_PAIR_EACH(TW_PAIR_SUMS_OF)
  for (; count >= 2; count -= 2, zp += 2 * TW_VECS) {
    const real16 a0 = (real16)(cx[p]), b0 = (real16)(cy[p]);
    p += step--;
    const real16 a1 = (real16)(cx[p]), b1 = (real16)(cy[p]);
    p += step--;
    TW_PAIR_EACH(TW_PAIR_TRIP_OF)
  }
  if (count > 0) {
    const real16 a0 = (real16)(cx[p]), b0 = (real16)(cy[p]);
    TW_PAIR_EACH(TW_PAIR_LAST_OF)
  }
  TW_PAIR_EACH(TW_PAIR_ADD_OF)
}

// A per-lane int mask as the mask of real16 selects (long16 lanes in double).
#ifdef TW_DOUBLE
inline mask16 lane_mask(int16 m) { return convert_long16(m); }
#else
inline mask16 lane_mask(int16 m) { return m; }
#endif

// The packed index of the unordered pair (a, b), a ≠ b.
inline int16 pair_index(int16 a, int16 b, int n) {
  const int16 lo = min(a, b), hi = max(a, b);
  return TW_PAIR_SLOT(lo, hi, n);
}
#define TW_GATHER16(a, i)                                                                                     \
  ((real16)((a)[(i).s0], (a)[(i).s1], (a)[(i).s2], (a)[(i).s3], (a)[(i).s4], (a)[(i).s5], (a)[(i).s6],        \
            (a)[(i).s7], (a)[(i).s8], (a)[(i).s9], (a)[(i).sa], (a)[(i).sb], (a)[(i).sc], (a)[(i).sd], (a)[(i).se], \
            (a)[(i).sf]))

// v(p, t) and its gradient ∇v (∂v/∂x, ∂v/∂y, complex) for the work-item's TW_VECS×TW_LANES points, same arguments
// as field_evaluate except col (4·n·TW_VECS vectors: the arrays of TW_GRADIENT_ARRAY) and acc (TW_ROW_SUMS·n·TW_VECS
// vectors when n > TW_COLUMN_BLOCK). Pixels per unit time, and per unit time.
//
// The weights W_t above are the exact ones over one common factor K(p), so with the normalisers (r_(1), r_(2),
// r_gmin, γ, γ', μ) held fixed, ∇ln W_t is exact: G_t = g_i + g_j for pair (i, j), g_g for a gradient feature,
// g_i = −α·δ_i / r_i. With u_t the similarity velocities (Eq. 3–4), v = Σ W_t u_t / Σ W_t and
//   ∂_d v = (Σ W_t c_t e_d + Σ W_t G_t^d (u_t − v)) / Σ W_t,   e_x = 1, e_y = i,
// the form of the CPU reference; Σ W_t (u_t − v) = 0 lets every G_t be shifted by one constant, here g* = g_k of
// the feature k nearest to p (of either kind), and velocities are taken relative to D* = D_k (u' = u − D*). Near k,
// g_k ~ 1/|δ_k| multiplies terms of weight ~1 whose u' ~ |δ_k| would come from cancelling O(|D|) values: float32
// rounding times g_k would grow without bound. So the pairs are taken in two sets:
//   - those of the nearest positional feature p, (p, j): weight 2γμ·z_p·z_j = ζ_p·z_j, u'_pj = D'_p + δ_p·c_pj
//     (= δ_p·c_pj with full relative precision when p = k, D'_p = 0), G' = h_p + g_j with h_p = g_p − g* (exactly 0
//     when p = k). Their sums over j: S_p = Σ z_j, R_p = Σ z_j·c_pj (row p of the loop below), T = Σ z_j·g_j and
//     Q_p = Σ z_j·g_j·c_pj (gathered per lane: p differs between lanes);
//   - the others, (i, j) with i, j ≠ p, at weights γμ·z°_i·z°_j ≤ μ = (r_(1) / r_(2))^h, whose G' = g_i + g_j − g*:
//     as w and u' are symmetric in i and j, Σ w·G'·u' = 2·Σ_i γμ·z°_i·g_i·X_i − g*·Σ w·u', with the full row sums
//     R°_i = Σ_{j≠i} z°_j·c_ij, S°_i = Σ_{j≠i} z°_j and X_i = D'_i·S°_i + δ_i·R°_i. g_i (i ≠ p) is bounded; g*
//     multiplies weights that vanish faster than it grows (α > 1), as in the CPU reference.
// The hot loop is R°_i alone, over full rows: two FMAs per ordered pair per 16 points, the row and column halves
// of the packed pairs (pair_row_sums, pair_column_sums), against six per unordered pair when every row also summed
// z_j·g_j·c_ij (the Q_i of each row). μ is applied per row (γμ·z°_i ≤ 1) so that products stay in range.
void field_evaluate_gradient(FieldShape s, __global const real* feat, __global const real* grad,
                             __global const real* cx, __global const real* cy, __global const real* flo,
                             __global const real* glo, __global real16* col, __global real16* acc, const real16* ox,
                             const real16* oy, const real16* px, const real16* py, real16* vx, real16* vy,
                             real16* gxx, real16* gxy, real16* gyx, real16* gyy) {
  const int mode = s.pow_mode;
  const real h = s.half_alpha;
  const real alpha = 2 * h;
  __global real16* zo = TW_GRADIENT_ARRAY(col, 0, s.n);
  __global real16* zgx = TW_GRADIENT_ARRAY(col, 1, s.n);
  __global real16* zgy = TW_GRADIENT_ARRAY(col, 2, s.n);
  __global real16* factors = TW_GRADIENT_ARRAY(col, 3, s.n);
  // The weights' normalisers, the positional features' r in zo, and the nearest feature k: δ_k, D_k, r_k.
  real16 rg_min[TW_VECS], r1[TW_VECS], r2[TW_VECS], z1[TW_VECS], pair_scale[TW_VECS], grad_scale[TW_VECS];
  real16 kdx[TW_VECS], kdy[TW_VECS], kux[TW_VECS], kuy[TW_VECS], kr[TW_VECS];
  field_normalisers(s, feat, grad, flo, glo, ox, oy, px, py, zo, TW_VECS, true, rg_min, r1, r2, z1, pair_scale,
                    grad_scale, kdx, kdy, kux, kuy, kr);
  // g* = g_k, by the nearest feature's own rule: a positional one is flat where its z is clamped.
  real16 gsx[TW_VECS], gsy[TW_VECS];
  TW_EACH_VEC(
    mask16 flat = (mask16)(0);
    if (s.n > 0) flat = (mask16)(kr[v] == r1[v]) & (mask16)(z1[v] >= (real16)(TW_ZMAX));
    const real16 fk = log_weight_factor(kr[v], (real16)(1) / kr[v], flat, alpha);
    gsx[v] = fk * kdx[v];
    gsy[v] = fk * kdy[v];
  );
  // Σ W u' (num), Σ W (den), Σ W c (cs), Σ W G'^d u' (nx_*, ny_*), Σ W G'^d (dx_w, dy_w).
  real16 num_x[TW_VECS], num_y[TW_VECS], den[TW_VECS], cs_x[TW_VECS], cs_y[TW_VECS];
  real16 nx_x[TW_VECS], nx_y[TW_VECS], ny_x[TW_VECS], ny_y[TW_VECS], dx_w[TW_VECS], dy_w[TW_VECS];
  TW_EACH_VEC(
    num_x[v] = num_y[v] = den[v] = cs_x[v] = cs_y[v] = (real16)(0);
    nx_x[v] = nx_y[v] = ny_x[v] = ny_y[v] = dx_w[v] = dy_w[v] = (real16)(0);
  );

  if (s.n > 1) {
    // The columns, and the nearest positional feature p of each lane: its index, δ_p, D'_p, h_p; Σ z°_j (= S_p)
    // and T = Σ z°_j·g_j.
    int16 pk[TW_VECS];
    real16 pdx[TW_VECS], pdy[TW_VECS], pex[TW_VECS], pey[TW_VECS], phx[TW_VECS], phy[TW_VECS];
    real16 sum_z[TW_VECS], tx[TW_VECS], ty[TW_VECS];
    TW_EACH_VEC(
      pk[v] = (int16)(-1);
      pdx[v] = pdy[v] = pex[v] = pey[v] = phx[v] = phy[v] = (real16)(0);
      sum_z[v] = tx[v] = ty[v] = (real16)(0);
    );
    for (int i = 0; i < s.n; ++i) {
      __global const real* f = feat + TW_POS_STRIDE * i;
      const real fx = f[TW_REC_HI_X], fy = f[TW_REC_HI_Y], lx = flo[2 * i], ly = flo[2 * i + 1];
      const real ux = f[TW_REC_D_X], uy = f[TW_REC_D_Y];
      TW_EACH_VEC(
        const real16 dx = feature_offset(ox[v], px[v], fx, lx);
        const real16 dy = feature_offset(oy[v], py[v], fy, ly);
        const real16 r = zo[i * TW_VECS + v];
        const real16 inv_r = (real16)(1) / r;
        const real16 z = min(pow_half_alpha(r2[v] * inv_r, mode, h), (real16)(TW_ZMAX));
        const real16 fi = log_weight_factor(r, inv_r, (mask16)(z >= (real16)(TW_ZMAX)), alpha);
        const int16 first = convert_int16(r == r1[v]) & (pk[v] < 0);  // p: the first at r_(1)
        const mask16 is_p = lane_mask(first);
        pk[v] = select(pk[v], (int16)(i), first);
        pdx[v] = select(pdx[v], dx, is_p);
        pdy[v] = select(pdy[v], dy, is_p);
        pex[v] = select(pex[v], (real16)(ux) - kux[v], is_p);
        pey[v] = select(pey[v], (real16)(uy) - kuy[v], is_p);
        // h_p = g_p − g*, exactly 0 where p is the nearest feature k itself
        const mask16 self = (mask16)(dx == kdx[v]) & (mask16)(dy == kdy[v]);
        phx[v] = select(phx[v], select(fma(fi, dx, -gsx[v]), (real16)(0), self), is_p);
        phy[v] = select(phy[v], select(fma(fi, dy, -gsy[v]), (real16)(0), self), is_p);
        const real16 zi = select(z, (real16)(0), is_p);
        zo[i * TW_VECS + v] = zi;
        zgx[i * TW_VECS + v] = zi * fi * dx;
        zgy[i * TW_VECS + v] = zi * fi * dy;
        factors[i * TW_VECS + v] = fi;
        sum_z[v] += zi;
        tx[v] = fma(zi * fi, dx, tx[v]);
        ty[v] = fma(zi * fi, dy, ty[v]);
      );
    }

    // Full rows R°_i in column blocks (the z° of a block stay in the L1 cache), from the last block; a row keeps
    // its partial sums in `acc` until its first block. Row p of each lane is R_p (its z°_p is 0: it adds nothing
    // else).
    real16 rpx[TW_VECS], rpy[TW_VECS];
    real16 onum_x[TW_VECS], onum_y[TW_VECS], oden[TW_VECS];  // the other pairs' Σ W u' and Σ W
    TW_EACH_VEC(rpx[v] = rpy[v] = onum_x[v] = onum_y[v] = oden[v] = (real16)(0);)
    for (int j0 = (s.n - 1) / TW_COLUMN_BLOCK * TW_COLUMN_BLOCK; j0 >= 0; j0 -= TW_COLUMN_BLOCK) {
      const int j1 = min(j0 + TW_COLUMN_BLOCK, s.n);
      for (int i = 0; i < s.n; ++i) {
        real16 rx[TW_VECS], ry[TW_VECS];
        __global real16* row_acc = acc + TW_ROW_SUMS * TW_VECS * i;
        if (j1 < s.n) {
          TW_EACH_VEC(
            rx[v] = row_acc[v];
            ry[v] = row_acc[TW_VECS + v];
          );
        } else {
          TW_EACH_VEC(rx[v] = ry[v] = (real16)(0);)
        }
        const int below = min(i, j1) - j0;  // columns j0 … of the block below the diagonal: pairs (j, i)
        if (below > 0) {
          const int p0 = TW_PAIR_SLOT(j0, i, s.n);
          TW_EACH_VEC(
            if (v % TW_PAIR_PASS == 0) {
              pair_column_sums(cx, cy, p0, s.n - j0 - 2, below, zo + j0 * TW_VECS, v, rx, ry);
            }
          );
        }
        const int first = max(i + 1, j0);  // and above it: pairs (i, j)
        if (first < j1) {
          const int row = TW_PAIR_SLOT(i, 0, s.n);
          TW_EACH_VEC(
            if (v % TW_PAIR_PASS == 0) {
              pair_row_sums(cx + row + first, cy + row + first, cx + row + j1, zo + first * TW_VECS, v, rx, ry);
            }
          );
        }
        if (j0 > 0) {
          TW_EACH_VEC(
            row_acc[v] = rx[v];
            row_acc[TW_VECS + v] = ry[v];
          );
          continue;
        }
        __global const real* f = feat + TW_POS_STRIDE * i;
        const real fx = f[TW_REC_HI_X], fy = f[TW_REC_HI_Y], lx = flo[2 * i], ly = flo[2 * i + 1];
        const real ux = f[TW_REC_D_X], uy = f[TW_REC_D_Y];
        TW_EACH_VEC(
          const mask16 at_p = lane_mask(pk[v] == (int16)(i));
          rpx[v] = select(rpx[v], rx[v], at_p);
          rpy[v] = select(rpy[v], ry[v], at_p);
          const real16 zi = zo[i * TW_VECS + v];
          const real16 wi = (real16)(0.5) * pair_scale[v] * zi;  // γμ·z°_i: ordered pairs
          const real16 si = sum_z[v] - zi;                          // S°_i
          const real16 dx = feature_offset(ox[v], px[v], fx, lx);
          const real16 dy = feature_offset(oy[v], py[v], fy, ly);
          const real16 fi = factors[i * TW_VECS + v];
          const real16 ex = (real16)(ux) - kux[v];  // D'_i
          const real16 ey = (real16)(uy) - kuy[v];
          const real16 xx = fma(ex, si, fma(dx, rx[v], -(dy * ry[v])));  // X_i
          const real16 xy = fma(ey, si, fma(dx, ry[v], dy * rx[v]));
          onum_x[v] = fma(wi, xx, onum_x[v]);
          onum_y[v] = fma(wi, xy, onum_y[v]);
          oden[v] = fma(wi, si, oden[v]);
          cs_x[v] = fma(wi, rx[v], cs_x[v]);
          cs_y[v] = fma(wi, ry[v], cs_y[v]);
          const real16 w2x = (real16)(2) * wi * fi * dx;  // 2γμ·z°_i·g_i
          const real16 w2y = (real16)(2) * wi * fi * dy;
          nx_x[v] = fma(w2x, xx, nx_x[v]);
          nx_y[v] = fma(w2x, xy, nx_y[v]);
          ny_x[v] = fma(w2y, xx, ny_x[v]);
          ny_y[v] = fma(w2y, xy, ny_y[v]);
          dx_w[v] = fma(w2x, si, dx_w[v]);
          dy_w[v] = fma(w2y, si, dy_w[v]);
        );
      }
    }

    // Q_p = Σ z°_j·g_j·c_pj, row p of each lane gathered (z°_p = 0 takes the diagonal out).
    real16 qxx[TW_VECS], qxy[TW_VECS], qyx[TW_VECS], qyy[TW_VECS];
    TW_EACH_VEC(qxx[v] = qxy[v] = qyx[v] = qyy[v] = (real16)(0);)
    for (int j = 0; j < s.n; ++j) {
      TW_EACH_VEC(
        const int16 at = select(pair_index(pk[v], (int16)(j), s.n), (int16)(0), pk[v] == (int16)(j) | pk[v] < 0);
        const real16 a = TW_GATHER16(cx, at);
        const real16 b = TW_GATHER16(cy, at);
        const real16 gx = zgx[j * TW_VECS + v], gy = zgy[j * TW_VECS + v];
        qxx[v] = fma(gx, a, qxx[v]);
        qxy[v] = fma(gx, b, qxy[v]);
        qyx[v] = fma(gy, a, qyx[v]);
        qyy[v] = fma(gy, b, qyy[v]);
      );
    }

    TW_EACH_VEC(
      // The other pairs: −g*·Σ W u', −g*·Σ W (their shift by g*).
      num_x[v] += onum_x[v];
      num_y[v] += onum_y[v];
      den[v] += oden[v];
      nx_x[v] = fma(-gsx[v], onum_x[v], nx_x[v]);
      nx_y[v] = fma(-gsx[v], onum_y[v], nx_y[v]);
      ny_x[v] = fma(-gsy[v], onum_x[v], ny_x[v]);
      ny_y[v] = fma(-gsy[v], onum_y[v], ny_y[v]);
      dx_w[v] = fma(-gsx[v], oden[v], dx_w[v]);
      dy_w[v] = fma(-gsy[v], oden[v], dy_w[v]);
      // p's pairs, ζ_p = 2γμ·z_p: u'_pj = D'_p + δ_p·c_pj, G' = h_p + g_j.
      const real16 zp = select((real16)(0), pair_scale[v] * z1[v], lane_mask(pk[v] >= (int16)(0)));
      const real16 xpx = fma(pex[v], sum_z[v], fma(pdx[v], rpx[v], -(pdy[v] * rpy[v])));  // Σ z_j u'_pj
      const real16 xpy = fma(pey[v], sum_z[v], fma(pdx[v], rpy[v], pdy[v] * rpx[v]));
      num_x[v] = fma(zp, xpx, num_x[v]);
      num_y[v] = fma(zp, xpy, num_y[v]);
      den[v] = fma(zp, sum_z[v], den[v]);
      cs_x[v] = fma(zp, rpx[v], cs_x[v]);
      cs_y[v] = fma(zp, rpy[v], cs_y[v]);
      // Σ z_j g_j u'_pj = D'_p·T + δ_p·Q_p (per derivative d), plus h_p·Σ z_j u'_pj
      nx_x[v] = fma(zp, fma(phx[v], xpx, fma(pex[v], tx[v], fma(pdx[v], qxx[v], -(pdy[v] * qxy[v])))), nx_x[v]);
      nx_y[v] = fma(zp, fma(phx[v], xpy, fma(pey[v], tx[v], fma(pdx[v], qxy[v], pdy[v] * qxx[v]))), nx_y[v]);
      ny_x[v] = fma(zp, fma(phy[v], xpx, fma(pex[v], ty[v], fma(pdx[v], qyx[v], -(pdy[v] * qyy[v])))), ny_x[v]);
      ny_y[v] = fma(zp, fma(phy[v], xpy, fma(pey[v], ty[v], fma(pdx[v], qyy[v], pdy[v] * qyx[v]))), ny_y[v]);
      dx_w[v] = fma(zp, fma(phx[v], sum_z[v], tx[v]), dx_w[v]);
      dy_w[v] = fma(zp, fma(phy[v], sum_z[v], ty[v]), dy_w[v]);
    );
  }

  // Gradient features: W_g = γ'·(r_gmin / r_g)^h, u'_g = D_g − D* + κ_g·δ_g, G'_g = g_g − g*.
  for (int g = 0; g < s.m; ++g) {
    __global const real* f = grad + TW_GRAD_STRIDE * g;
    const real fx = f[TW_REC_HI_X], fy = f[TW_REC_HI_Y], lx = glo[2 * g], ly = glo[2 * g + 1];
    const real ux = f[TW_REC_D_X], uy = f[TW_REC_D_Y], kx = f[TW_REC_KAPPA_X], ky = f[TW_REC_KAPPA_Y];
    TW_EACH_VEC(
      const real16 dx = feature_offset(ox[v], px[v], fx, lx);
      const real16 dy = feature_offset(oy[v], py[v], fy, ly);
      const real16 r = fma(dx, dx, dy * dy);
      const real16 w = gradient_weight(r, rg_min[v], grad_scale[v], mode, h);
      const real16 fg = log_weight_factor(r, (real16)(1) / r, (mask16)(0), alpha);
      const mask16 self = (mask16)(dx == kdx[v]) & (mask16)(dy == kdy[v]);
      const real16 hx = select(fma(fg, dx, -gsx[v]), (real16)(0), self);
      const real16 hy = select(fma(fg, dy, -gsy[v]), (real16)(0), self);
      const real16 ex = fma((real16)(kx), dx, fma((real16)(-ky), dy, (real16)(ux) - kux[v]));
      const real16 ey = fma((real16)(kx), dy, fma((real16)(ky), dx, (real16)(uy) - kuy[v]));
      num_x[v] = fma(w, ex, num_x[v]);
      num_y[v] = fma(w, ey, num_y[v]);
      den[v] += w;
      cs_x[v] = fma(w, (real16)(kx), cs_x[v]);
      cs_y[v] = fma(w, (real16)(ky), cs_y[v]);
      const real16 whx = w * hx;
      const real16 why = w * hy;
      nx_x[v] = fma(whx, ex, nx_x[v]);
      nx_y[v] = fma(whx, ey, nx_y[v]);
      ny_x[v] = fma(why, ex, ny_x[v]);
      ny_y[v] = fma(why, ey, ny_y[v]);
      dx_w[v] += whx;
      dy_w[v] += why;
    );
  }

  TW_EACH_VEC(
    const real16 inv = (real16)(1) / den[v];
    const real16 wx = num_x[v] * inv;  // v'
    const real16 wy = num_y[v] * inv;
    vx[v] = wx + kux[v];
    vy[v] = wy + kuy[v];
    gxx[v] = (cs_x[v] + fma(-wx, dx_w[v], nx_x[v])) * inv;
    gxy[v] = (cs_y[v] + fma(-wy, dx_w[v], nx_y[v])) * inv;
    gyx[v] = (ny_x[v] - fma(wx, dy_w[v], cs_y[v])) * inv;
    gyy[v] = (cs_x[v] + fma(-wy, dy_w[v], ny_y[v])) * inv;
  );
}
