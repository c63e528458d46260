// The velocity field of Eq. 2–7 (DESIGN.md §1) for TW_VECS×16 points per work-item, in explicit 16-lane vectors
// (PoCL 3.1 does not vectorise across work-items when a kernel has inner loops). Same field as the CPU
// reference (core/src/velocity_field.cpp), normalised so that every weight is finite and ≤ 1 near features.
//
// Compile-time options: TW_DOUBLE (double instead of float arithmetic), TW_VECS (vectors per work-item: 4).
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

#ifdef TW_DOUBLE
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef double real;
typedef double16 real16;
typedef long16 mask16;
#define TW_ZMAX 1e150
#define TW_MIN_STEP 1e-12
#else
typedef float real;
typedef float16 real16;
typedef int16 mask16;
#define TW_ZMAX 1e15f
#define TW_MIN_STEP 1e-6f
#endif

// Four 16-lane vectors per work-item, written out by TW_EACH_VEC: PoCL's compiler does not unroll even short
// constant loops, and arrays indexed in a loop would stay in memory instead of registers.
#ifndef TW_VECS
#define TW_VECS 4
#endif
#if TW_VECS != 4
#error "the kernels are written for TW_VECS == 4"
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

#define TW_LANES 16
// Columns of the pair loop per block: TW_VECS·64 bytes of z per column, 32 KiB per block in float32.
#define TW_COLUMN_BLOCK 128
#define TW_POS_STRIDE 6   // F_hi.x, F_hi.y, F_lo.x, F_lo.y, D.x, D.y
#define TW_GRAD_STRIDE 8  // F_hi.x, F_hi.y, F_lo.x, F_lo.y, D.x, D.y, κ.x, κ.y

// Exponent modes for q^h, h = α/2: the common α get sqrt/multiply forms (exact at 0 and ∞, no log).
#define TW_POW_GENERAL 0
#define TW_POW_ALPHA2 1
#define TW_POW_ALPHA3 2
#define TW_POW_ALPHA1_5 3
#define TW_POW_ALPHA1 4
#define TW_POW_ALPHA4 5

inline real16 pow_half_alpha(real16 q, int mode, real h) {
  switch (mode) {
    case TW_POW_ALPHA2: return q;
    case TW_POW_ALPHA3: return q * sqrt(q);
    case TW_POW_ALPHA1_5: return sqrt(q * sqrt(q));
    case TW_POW_ALPHA1: return sqrt(q);
    case TW_POW_ALPHA4: return q * q;
    default: return pow(q, (real16)(h));
  }
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

// The part of the field that depends on t only, for one work-item: c_ij(t) for every unordered pair (16 pairs
// per vector operation) and F_lo + t·D for every feature. Pair records: SoA of ΔF(0) = F_j(0) − F_i(0) and
// ΔD = D_j − D_i, so ΔF(t) = ΔF(0) + t·ΔD and c_ij = ΔD / ΔF(t) (Eq. 2, complex division).
void field_coefficients(real t, FieldShape s, __global const real* feat, __global const real* grad,
                        __global const real* pairs, __global real* cx, __global real* cy, __global real* flo,
                        __global real* glo) {
  __global const real* f0x = pairs;
  __global const real* f0y = pairs + s.pairs16;
  __global const real* ddx = pairs + 2 * s.pairs16;
  __global const real* ddy = pairs + 3 * s.pairs16;
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
    flo[2 * i] = fma(t, f[4], f[2]);
    flo[2 * i + 1] = fma(t, f[5], f[3]);
  }
  for (int g = 0; g < s.m; ++g) {
    __global const real* f = grad + TW_GRAD_STRIDE * g;
    glo[2 * g] = fma(t, f[4], f[2]);
    glo[2 * g + 1] = fma(t, f[5], f[3]);
  }
}

// v(p, t) for the work-item's TW_VECS×16 points: origins (ox, oy), offsets (px, py); coefficients from
// field_coefficients at the same t. z: scratch of n·TW_VECS vectors; acc: of 2·n·TW_VECS vectors when
// n > TW_COLUMN_BLOCK. Pixels per unit time.
void field_evaluate(FieldShape s, __global const real* feat, __global const real* grad,
                    __global const real* cx, __global const real* cy, __global const real* flo,
                    __global const real* glo, __global real16* z, __global real16* acc, const real16* ox, const real16* oy,
                    const real16* px, const real16* py, real16* vx, real16* vy) {
  const int mode = s.pow_mode;
  const real h = s.half_alpha;
  real16 num_x[TW_VECS], num_y[TW_VECS], den[TW_VECS], rg_min[TW_VECS];
  TW_EACH_VEC(
    num_x[v] = (real16)(0);
    num_y[v] = (real16)(0);
    den[v] = (real16)(0);
    rg_min[v] = (real16)(INFINITY);
  );

  // Nearest gradient feature (squared distance). min/max rather than fmin/fmax in the O(n) passes: one
  // instruction instead of four (fmin's NaN rules); the values are ≥ 0 or +∞, a NaN input fails later anyway.
  for (int g = 0; g < s.m; ++g) {
    __global const real* f = grad + TW_GRAD_STRIDE * g;
    const real fx = f[0], fy = f[1], lx = glo[2 * g], ly = glo[2 * g + 1];
    TW_EACH_VEC(
      const real16 dx = (ox[v] - fx) + (px[v] - lx);
      const real16 dy = (oy[v] - fy) + (py[v] - ly);
      rg_min[v] = min(rg_min[v], fma(dx, dx, dy * dy));
    );
  }

  real16 grad_scale[TW_VECS];  // γ'
  TW_EACH_VEC(grad_scale[v] = (real16)(1);)

  if (s.n > 0) {
    // Squared distances into z, and the two nearest positional features.
    real16 r1[TW_VECS], r2[TW_VECS];
    TW_EACH_VEC(r1[v] = r2[v] = (real16)(INFINITY);)
    for (int i = 0; i < s.n; ++i) {
      __global const real* f = feat + TW_POS_STRIDE * i;
      const real fx = f[0], fy = f[1], lx = flo[2 * i], ly = flo[2 * i + 1];
      TW_EACH_VEC(
        const real16 dx = (ox[v] - fx) + (px[v] - lx);
        const real16 dy = (oy[v] - fy) + (py[v] - ly);
        const real16 r = fma(dx, dx, dy * dy);
        z[i * TW_VECS + v] = r;
        r2[v] = min(r2[v], max(r1[v], r));
        r1[v] = min(r1[v], r);
      );
    }
    real16 pair_scale[TW_VECS];  // 2·γ·μ
    if (s.m == 0) {  // no gradient feature: γ = 1, no logarithms
      TW_EACH_VEC(pair_scale[v] = (real16)(2) / min(pow_half_alpha(r2[v] / r1[v], mode, h), (real16)(TW_ZMAX));)
    } else {
      TW_EACH_VEC(
        const real16 z1 = min(pow_half_alpha(r2[v] / r1[v], mode, h), (real16)(TW_ZMAX));
        const real16 ln_x =
            (real16)(h) * (log(r1[v]) + log(r2[v]) - log(rg_min[v]) + (real16)(s.log_inv_length2));
        pair_scale[v] = (real16)(2) * exp(fmin((real16)(0), -ln_x)) / z1;
        grad_scale[v] = exp(fmin((real16)(0), ln_x));
      );
    }
    for (int i = 0; i < s.n; ++i) {
      TW_EACH_VEC(
        z[i * TW_VECS + v] = min(pow_half_alpha(r2[v] / z[i * TW_VECS + v], mode, h), (real16)(TW_ZMAX));
      );
    }

    // Rows from the last, so that S_i = Σ_{j>i} z_j grows by one term per row; columns in blocks of
    // TW_COLUMN_BLOCK features, also from the last, so that the z of a block stay in the L1 cache while every
    // row runs over them. A row whose columns continue in an earlier-visited block keeps its partial R_i in
    // `acc` (2·TW_VECS vectors per row, used only when n > TW_COLUMN_BLOCK).
    real16 row_sum[TW_VECS];
    TW_EACH_VEC(row_sum[v] = (real16)(0);)
    for (int j0 = (s.n - 1) / TW_COLUMN_BLOCK * TW_COLUMN_BLOCK; j0 >= 0; j0 -= TW_COLUMN_BLOCK) {
      const int j1 = min(j0 + TW_COLUMN_BLOCK, s.n);
      for (int i = j1 - 2; i >= 0; --i) {
        const bool complete = i + 1 >= j0;  // no column of row i lies in a block still to come
        real16 rx[TW_VECS], ry[TW_VECS];
        __global real16* row_acc = acc + 2 * TW_VECS * i;
        if (j1 < s.n) {
          TW_EACH_VEC(
            rx[v] = row_acc[v];
            ry[v] = row_acc[TW_VECS + v];
          );
        } else {
          TW_EACH_VEC(
            rx[v] = (real16)(0);
            ry[v] = (real16)(0);
          );
        }
        // The hot loop: row i of the packed pairs (it starts at i·n − i(i+1)/2) against z_j over the block's
        // columns j > i. Pointers advance instead of indices (fewer integer operations), two pairs per trip.
        const int first = complete ? i + 1 : j0;
        const int row = i * s.n - i * (i + 1) / 2 - (i + 1);
        __global const real* rcx = cx + row + first;
        __global const real* rcy = cy + row + first;
        __global const real16* zp = z + first * TW_VECS;
        __global const real* const row_end = cx + row + j1;
        for (; rcx + 1 < row_end; rcx += 2, rcy += 2, zp += 2 * TW_VECS) {
          const real16 a0 = (real16)(rcx[0]), b0 = (real16)(rcy[0]);
          const real16 a1 = (real16)(rcx[1]), b1 = (real16)(rcy[1]);
          TW_EACH_VEC(
            const real16 z0 = zp[v];
            const real16 z1 = zp[TW_VECS + v];
            rx[v] = fma(z1, a1, fma(z0, a0, rx[v]));
            ry[v] = fma(z1, b1, fma(z0, b0, ry[v]));
          );
        }
        if (rcx < row_end) {
          const real16 a0 = (real16)(rcx[0]), b0 = (real16)(rcy[0]);
          TW_EACH_VEC(
            rx[v] = fma(zp[v], a0, rx[v]);
            ry[v] = fma(zp[v], b0, ry[v]);
          );
        }
        if (!complete) {
          TW_EACH_VEC(
            row_acc[v] = rx[v];
            row_acc[TW_VECS + v] = ry[v];
          );
          continue;
        }
        __global const real* f = feat + TW_POS_STRIDE * i;
        const real fx = f[0], fy = f[1], lx = flo[2 * i], ly = flo[2 * i + 1], ux = f[4], uy = f[5];
        TW_EACH_VEC(
          row_sum[v] += z[(i + 1) * TW_VECS + v];
          const real16 dx = (ox[v] - fx) + (px[v] - lx);
          const real16 dy = (oy[v] - fy) + (py[v] - ly);
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
    const real fx = f[0], fy = f[1], lx = glo[2 * g], ly = glo[2 * g + 1];
    const real ux = f[4], uy = f[5], kx = f[6], ky = f[7];
    TW_EACH_VEC(
      const real16 dx = (ox[v] - fx) + (px[v] - lx);
      const real16 dy = (oy[v] - fy) + (py[v] - ly);
      const real16 r = fma(dx, dx, dy * dy);
      const real16 q = select(rg_min[v] / r, (real16)(1), (mask16)(r <= rg_min[v]));
      const real16 w = grad_scale[v] * pow_half_alpha(q, mode, h);
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
