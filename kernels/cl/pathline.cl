// Pathline integration of dp/dt = v(p, t) (Eq. 1) on the device: Dormand–Prince 5(4) with error control, one
// step sequence per work-item (its TW_VECS×TW_LANES points), the tableau and step controller of the CPU
// reference (core/include/texwarp/core/dormand_prince.hpp, through the host's prelude), plus step caps at near-collisions of feature trajectories and compensated sums of
// the positions. Needs velocity_field.cl before it in the same program.
//
// With TW_JACOBIAN (in the host's prelude) the kernel also integrates the variational equation dJ/dt = ∇v(p, t)·J,
// J(t_start) = I, through the same stages (J's stage values built from its stage derivatives exactly like the
// positions'), giving the flow's Jacobian at each start point; as in the CPU reference, J's error estimate
// (weighted by TW_JACOBIAN_ERROR_LENGTH, pixels) steers the step along with the positions'. J's sums are plain:
// its float32 rounding over a pathline's steps (~1e-6 relative) is far below its truncation error at the
// tolerances that run in float32.

// Dormand & Prince (1980): the last stage is evaluated at the 5th-order solution (FSAL). kError: 5th-order weights
// minus the embedded 4th-order ones, the local error estimate.
#define TW_DP_LAST (TW_DP_STAGES - 1)
__constant real kStageTime[TW_DP_STAGES] = TW_DP_C;
__constant real kStage[TW_DP_STAGES][TW_DP_LAST] = TW_DP_A;
__constant real kError[TW_DP_STAGES] = TW_DP_E;

inline real horizontal_max(real16 x) {
#ifdef TW_DOUBLE
  double8 a = fmax(x.lo, x.hi);
#else
  float8 a = fmax(x.lo, x.hi);
#endif
  a.lo = fmax(a.lo, a.hi);
  a.s01 = fmax(a.s01, a.s23);
  return fmax(a.s0, a.s1);
}

// One work-item moves TW_VECS×TW_LANES points from t_start to t_end. Point k of work-item w is element
// w·TW_VECS·TW_LANES + k of the SoA arrays: origin (org_x, org_y), offset from it (off_x, off_y), overwritten with
// the end offset. local_tol: allowed local error per unit time (pixels); first_step: the segment's first step
// (dormand_prince::first_step). Scratch: scratch_stride reals per work-item, laid out by the host (tile_plan.hpp):
// cx, cy, flo, glo, then z at z_offset and acc at acc_offset.
// status gets TW_STATUS_STRIDE ints per work-item: a TW_STATUS_* code and the number of field evaluations.
// event_records: `events` records (time, width) of near-collisions of feature trajectories, which cap the step
// size around those times. The parameter list is the host's PathlineKernelArgs (pathline_kernel_args.hpp).
// With TW_JACOBIAN: z_offset locates field_evaluate_gradient's arrays instead of z, and jacobian gets per
// work-item TW_JACOBIAN_COMPONENTS·TW_VECS·TW_LANES reals: ∂x/∂x, ∂y/∂x, ∂x/∂y, ∂y/∂y of the end point
// (TW_VECS·TW_LANES each, points in order); without it, jacobian is not touched.
__kernel void flow_pathlines(int n, int m, int pairs16, int pow_mode, real half_alpha, real log_inv_length2,
                             __global const real* feat, __global const real* grad, __global const real* pairs,
                             real t_start, real t_end, real local_tol, real first_step, __global const real* org_x,
                             __global const real* org_y, __global real* off_x, __global real* off_y,
                             __global real* scratch, int scratch_stride, int z_offset, int acc_offset,
                             int events, __global const real* event_records, __global int* status,
                             __global real* jacobian) {
  const int w = get_global_id(0);
  const FieldShape s = {n, m, pairs16, pow_mode, half_alpha, log_inv_length2};
  __global real* slot = scratch + (size_t)w * (size_t)scratch_stride;
  __global real* cx = slot;
  __global real* cy = slot + pairs16;
  __global real* flo = slot + 2 * pairs16;
  __global real* glo = flo + 2 * n;
  __global real16* z = (__global real16*)(slot + z_offset);
  __global real16* acc = (__global real16*)(slot + acc_offset);

  real16 ox[TW_VECS], oy[TW_VECS], px[TW_VECS], py[TW_VECS];
  TW_EACH_VEC(
    const size_t at = (size_t)w * TW_VECS + v;
    ox[v] = vload16(at, org_x);
    oy[v] = vload16(at, org_y);
    px[v] = vload16(at, off_x);
    py[v] = vload16(at, off_y);
  );

  real16 kx[TW_DP_STAGES][TW_VECS], ky[TW_DP_STAGES][TW_VECS];
  real16 yx[TW_VECS], yy[TW_VECS];
  // Position increments of the step (5th-order solution) and the compensation of their running sum (Kahan):
  // the offsets grow by many small steps, and float32 rounding of each sum would otherwise accumulate.
  real16 inc_x[TW_VECS], inc_y[TW_VECS], comp_x[TW_VECS], comp_y[TW_VECS];
  TW_EACH_VEC(
    comp_x[v] = (real16)(0);
    comp_y[v] = (real16)(0);
  );
  const real sign = t_end > t_start ? (real)(1) : (real)(-1);
  real t = t_start;
  real h = first_step;
  int code = TW_STATUS_OK;
  int evaluations = 1;
  int steps = 0;

#ifdef TW_JACOBIAN
  // J's columns (∂p/∂x, ∂p/∂y) as (jxx, jxy), (jyx, jyy); the stage derivatives of the four, and J at the
  // latest stage (after the last: the step's 5th-order solution).
  real16 jxx[TW_VECS], jxy[TW_VECS], jyx[TW_VECS], jyy[TW_VECS];
  real16 kj[TW_DP_STAGES][TW_JACOBIAN_COMPONENTS][TW_VECS], jt[TW_JACOBIAN_COMPONENTS][TW_VECS];
  real16 dvxx[TW_VECS], dvxy[TW_VECS], dvyx[TW_VECS], dvyy[TW_VECS];  // ∇v: ∂v/∂x, ∂v/∂y (complex)
  TW_EACH_VEC(
    jxx[v] = jyy[v] = (real16)(1);
    jxy[v] = jyx[v] = (real16)(0);
  );
#endif

  field_coefficients(t, s, feat, grad, pairs, cx, cy, flo, glo);
#ifdef TW_JACOBIAN
  field_evaluate_gradient(s, feat, grad, cx, cy, flo, glo, z, acc, ox, oy, px, py, kx[0], ky[0], dvxx, dvxy, dvyx,
                          dvyy);
  TW_EACH_VEC(
    kj[0][0][v] = dvxx[v];
    kj[0][1][v] = dvxy[v];
    kj[0][2][v] = dvyx[v];
    kj[0][3][v] = dvyy[v];
  );
#else
  field_evaluate(s, feat, grad, cx, cy, flo, glo, z, acc, ox, oy, px, py, kx[0], ky[0]);
#endif

  while (sign * (t_end - t) > 0) {
    if (++steps > TW_MAX_STEPS) {
      code = TW_STATUS_TOO_MANY_STEPS;
      break;
    }
    // Near-collisions: while two trajectories pass close, c_ij(t) and with it the field change within a time
    // of about their width; a step may end at such a time but not jump over it, and near it stays ≤ the width.
    for (int e = 0; e < events; ++e) {
      const real gap = fabs(event_records[TW_EVENT_STRIDE * e + TW_EVENT_TIME] - t);
      h = fmin(h, fmax(event_records[TW_EVENT_STRIDE * e + TW_EVENT_WIDTH], gap));
    }
    bool last = false;
    if (h >= sign * (t_end - t)) {
      h = sign * (t_end - t);
      last = true;
    }
    const real hs = sign * h;
    for (int st = 1; st < TW_DP_STAGES; ++st) {
      const real ts = (st == TW_DP_LAST && last) ? t_end : t + kStageTime[st] * hs;
      TW_EACH_VEC(
        real16 ax = (real16)(0), ay = (real16)(0);
        for (int j = 0; j < st; ++j) {
          ax = fma((real16)(kStage[st][j]), kx[j][v], ax);
          ay = fma((real16)(kStage[st][j]), ky[j][v], ay);
        }
        inc_x[v] = (real16)(hs) * ax;
        inc_y[v] = (real16)(hs) * ay;
        yx[v] = px[v] + inc_x[v];
        yy[v] = py[v] + inc_y[v];
      );
      field_coefficients(ts, s, feat, grad, pairs, cx, cy, flo, glo);
#ifdef TW_JACOBIAN
      field_evaluate_gradient(s, feat, grad, cx, cy, flo, glo, z, acc, ox, oy, yx, yy, kx[st], ky[st], dvxx, dvxy,
                              dvyx, dvyy);
      // J at the stage, and its derivative ∇v·J (∇v applied to each column).
      TW_EACH_VEC(
        real16 a0 = (real16)(0), a1 = (real16)(0), a2 = (real16)(0), a3 = (real16)(0);
        for (int j = 0; j < st; ++j) {
          const real16 c = (real16)(kStage[st][j]);
          a0 = fma(c, kj[j][0][v], a0);
          a1 = fma(c, kj[j][1][v], a1);
          a2 = fma(c, kj[j][2][v], a2);
          a3 = fma(c, kj[j][3][v], a3);
        }
        const real16 hv = (real16)(hs);
        jt[0][v] = fma(hv, a0, jxx[v]);
        jt[1][v] = fma(hv, a1, jxy[v]);
        jt[2][v] = fma(hv, a2, jyx[v]);
        jt[3][v] = fma(hv, a3, jyy[v]);
        kj[st][0][v] = fma(dvxx[v], jt[0][v], dvyx[v] * jt[1][v]);
        kj[st][1][v] = fma(dvxy[v], jt[0][v], dvyy[v] * jt[1][v]);
        kj[st][2][v] = fma(dvxx[v], jt[2][v], dvyx[v] * jt[3][v]);
        kj[st][3][v] = fma(dvxy[v], jt[2][v], dvyy[v] * jt[3][v]);
      );
#else
      field_evaluate(s, feat, grad, cx, cy, flo, glo, z, acc, ox, oy, yx, yy, kx[st], ky[st]);
#endif
    }
    evaluations += TW_DP_LAST;

    // Error of the step: the largest over the work-item's points (NaN counts as failure).
    real err = 0;
    bool finite = true;
    TW_EACH_VEC(
      real16 ex = (real16)(0), ey = (real16)(0);
      for (int j = 0; j < TW_DP_STAGES; ++j) {
        ex = fma((real16)(kError[j]), kx[j][v], ex);
        ey = fma((real16)(kError[j]), ky[j][v], ey);
      }
      const real16 e = (real16)(h) * sqrt(fma(ex, ex, ey * ey));
      finite = finite && !any(isnan(e) || isinf(e));
      err = fmax(err, horizontal_max(e));
#ifdef TW_JACOBIAN
      // J's error counted as the position error it makes TW_JACOBIAN_ERROR_LENGTH pixels away (the CPU's
      // kJacobianErrorLengthPx): a point moving with a feature has no position error, its J still has one.
      real16 e0 = (real16)(0), e1 = (real16)(0), e2 = (real16)(0), e3 = (real16)(0);
      for (int j = 0; j < TW_DP_STAGES; ++j) {
        const real16 c = (real16)(kError[j]);
        e0 = fma(c, kj[j][0][v], e0);
        e1 = fma(c, kj[j][1][v], e1);
        e2 = fma(c, kj[j][2][v], e2);
        e3 = fma(c, kj[j][3][v], e3);
      }
      const real16 ej = (real16)(h * TW_JACOBIAN_ERROR_LENGTH) * sqrt(fmax(fma(e0, e0, e1 * e1), fma(e2, e2, e3 * e3)));
      finite = finite && !any(isnan(ej) || isinf(ej));
      err = fmax(err, horizontal_max(ej));
      const real16 jsum = (jt[0][v] + jt[1][v]) + (jt[2][v] + jt[3][v]);
      finite = finite && !any(isnan(jsum) || isinf(jsum));
#endif
    );
    if (!finite) {
      code = TW_STATUS_NON_FINITE;
      break;
    }
    const real allowed = local_tol * h;
    const real factor = err == 0 ? (real)(TW_MAX_GROWTH)
                                 : clamp((real)(TW_SAFETY) * sqrt(sqrt(allowed / err)), (real)(TW_MAX_SHRINK),
                                         (real)(TW_MAX_GROWTH));
    if (err <= allowed) {
      t = last ? t_end : t + hs;
      TW_EACH_VEC(
        const real16 dx = inc_x[v] - comp_x[v];
        const real16 dy = inc_y[v] - comp_y[v];
        const real16 sx = px[v] + dx;
        const real16 sy = py[v] + dy;
        comp_x[v] = (sx - px[v]) - dx;
        comp_y[v] = (sy - py[v]) - dy;
        px[v] = sx;
        py[v] = sy;
        kx[0][v] = kx[TW_DP_LAST][v];
        ky[0][v] = ky[TW_DP_LAST][v];
#ifdef TW_JACOBIAN
        jxx[v] = jt[0][v];
        jxy[v] = jt[1][v];
        jyx[v] = jt[2][v];
        jyy[v] = jt[3][v];
        for (int c = 0; c < TW_JACOBIAN_COMPONENTS; ++c) kj[0][c][v] = kj[TW_DP_LAST][c][v];
#endif
      );
      h *= factor;
    } else {
      h *= fmin(factor, (real)(1));
      if (h < (real)(TW_MIN_STEP)) {
        code = TW_STATUS_STEP_COLLAPSE;
        break;
      }
    }
  }

  TW_EACH_VEC(
    const size_t at = (size_t)w * TW_VECS + v;
    vstore16(px[v] - comp_x[v], at, off_x);
    vstore16(py[v] - comp_y[v], at, off_y);
#ifdef TW_JACOBIAN
    const size_t item = (size_t)w * TW_JACOBIAN_COMPONENTS * TW_VECS;
    vstore16(jxx[v], item + v, jacobian);
    vstore16(jxy[v], item + TW_VECS + v, jacobian);
    vstore16(jyx[v], item + 2 * TW_VECS + v, jacobian);
    vstore16(jyy[v], item + 3 * TW_VECS + v, jacobian);
#endif
  );
  status[TW_STATUS_STRIDE * w + TW_STATUS_CODE] = code;
  status[TW_STATUS_STRIDE * w + TW_STATUS_EVALUATIONS] = evaluations;
}
