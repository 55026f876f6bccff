/*
 * plant_star.c - the star-point voltage of the star-connected machine
 * (Fabbri 2022, section 2.3.1) and its measurement.
 *
 * With no star-point current (sum of i_abc = 0) the machine equation
 * v_XO - v_NO T^T = R i + L di/dt + omega_e dL/dtheta_e i + e fixes v_NO:
 * T L^-1 (...) = T di/dt = 0 gives
 *   v_NO = G_c (v_XO - R i - omega_e dL/dtheta_e i - e),
 *   G_c  = L_Sigma / (L_Sigma T^T),  L_Sigma = T adj(L)          (2.64), (2.90)
 * with the (3.3) inductance matrix L(theta_e) (plant.h: plant_aniso_t).
 * This is the static divider of the star point at every instant: at a
 * switching edge v_NO jumps by G_c times the step of the leg potentials,
 * so the DFC signal (2.101) emerges from two samples around the edge; the
 * slow terms (back-EMF, resistive, dL/dt) are continuous and cancel in the
 * difference (2.92). Without anisotropy (aniso.enabled = 0, the (2.31)
 * matrix, singular) the star point is the mean of the leg potentials.
 * The measurement circuit is a first-order low-pass of time constant
 * star_tau, integrated exactly for an input linear over each step of the
 * switching model (first-order hold); the samples go through the star
 * channel's ADC in plant_star_read().
 */
#include "plant_internal.h"

#include <math.h>

/* the load's scale of the 2theta terms is held within these (the matrix is
 * checked at both ends) */
#define STAR_K_MIN 0.5
#define STAR_K_MAX 2.0

/* The (3.3) matrix, its self terms at xs = 2 theta_e (+ their load
 * shift), its mutual terms at xm, and its derivative with respect to
 * theta_e; xs and xm given by their cos and sin. The other phases' angles
 * are xs + q, xs + 2 q, xm +- q (q = 2 pi / 3) by angle addition with
 * cos q = -1/2, sin q = sqrt(3)/2: two angles instead of twelve libm
 * calls per derivative of the switching model. */
static void star_matrix_of(double l0, double l2, double m0, double m2, double cs, double ss,
                           double cm, double sm, double L[3][3], double dL[3][3]) {
  const double h = PLANT_SQRT3_2;
  const double c_self[3] = {cs, -0.5 * cs - h * ss, -0.5 * cs + h * ss};
  const double s_self[3] = {ss, -0.5 * ss + h * cs, -0.5 * ss - h * cs};
  /* ab at xm - q, ac at xm + q, bc at xm */
  const double c_mut[3] = {-0.5 * cm + h * sm, -0.5 * cm - h * sm, cm};
  const double s_mut[3] = {-0.5 * sm - h * cm, -0.5 * sm + h * cm, sm};
  for (int k = 0; k < 3; k++) {
    L[k][k] = l0 + l2 * c_self[k];
    dL[k][k] = -2.0 * l2 * s_self[k];
  }
  const int r[3] = {0, 0, 1}, c[3] = {1, 2, 2};
  for (int k = 0; k < 3; k++) {
    L[r[k]][c[k]] = L[c[k]][r[k]] = m0 + m2 * c_mut[k];
    dL[r[k]][c[k]] = dL[c[k]][r[k]] = -2.0 * m2 * s_mut[k];
  }
}

/* The load scale's range: the machine's (plant_aniso_t), else the default. */
static void star_k_range(const plant_aniso_t *an, double *lo, double *hi) {
  *lo = an->k_min > 0.0 ? an->k_min : STAR_K_MIN;
  *hi = an->k_max > 0.0 ? an->k_max : STAR_K_MAX;
}

/* The load scale 1 + amp_iq |i_q|, held within its range. */
static double star_k(const plant_aniso_t *an, double i_q) {
  double k = 1.0 + an->amp_iq * fabs(i_q), lo, hi;
  star_k_range(an, &lo, &hi);
  return k < lo ? lo : (k > hi ? hi : k);
}

/* at 2 (theta_e + shift) + phi_self i_q (self terms), + phi_mut i_q
 * (mutual terms), the 2theta terms scaled by the load; c, s: cos and sin
 * of theta_e. 2 theta_e by the double angle, turned by the shift and the
 * load's angles only when they are not zero (libm then, once each). */
static void star_matrix(const plant_t *pl, double c, double s, double i_q, double L[3][3],
                        double dL[3][3]) {
  const plant_aniso_t *an = &pl->p.machine.aniso;
  const double k = star_k(an, i_q);
  const double c2 = c * c - s * s, s2 = 2.0 * c * s;
  /* mut: star_mutual_follows_self */
  const double rs = 2.0 * an->shift + an->phi_self * i_q, rm = 2.0 * an->shift + an->phi_mut * i_q;
  double cs = c2, ss = s2, cm = c2, sm = s2;
  if (rs != 0.0) {
    const double cr = cos(rs), sr = sin(rs);
    cs = c2 * cr - s2 * sr;
    ss = s2 * cr + c2 * sr;
  }
  if (rm == rs) {
    cm = cs;
    sm = ss;
  } else if (rm != 0.0) {
    const double cr = cos(rm), sr = sin(rm);
    cm = c2 * cr - s2 * sr;
    sm = s2 * cr + c2 * sr;
  }
  star_matrix_of(pl->aux.l0, k * pl->aux.l2, an->m0, k * an->m2, cs, ss, cm, sm, L, dL);
}

/* The (3.3) matrix with its 2theta terms scaled by k and the mutual ones
 * turned by dx from the self ones is positive definite at every angle
 * (leading minors, checked every degree of 2 theta_e). */
static int star_pd(double l0, double l2, double m0, double m2, double k, double dx) {
  for (int d = 0; d < 360; d++) {
    double L[3][3], dL[3][3];
    const double x = d * (PLANT_PI / 180.0);
    star_matrix_of(l0, k * l2, m0, k * m2, cos(x), sin(x), cos(x + dx), sin(x + dx), L, dL);
    const double d2 = L[0][0] * L[1][1] - L[0][1] * L[1][0];
    const double d3 = L[0][0] * (L[1][1] * L[2][2] - L[1][2] * L[2][1]) -
                      L[0][1] * (L[1][0] * L[2][2] - L[1][2] * L[2][0]) +
                      L[0][2] * (L[1][0] * L[2][1] - L[1][1] * L[2][0]);
    if (!(L[0][0] > 0.0 && d2 > 0.0 && d3 > 0.0)) {
      return 0;
    }
  }
  return 1;
}

/* The matrix from (ld, lq, m0, m2) must be an inductance matrix: positive
 * definite at every angle, and carry the position (L2 != M2, first
 * condition of (3.7)). With a load scale, at both ends of its range (the
 * matrix is linear in the scale: positive definite at both ends is
 * positive definite between). The self and mutual terms turned apart by
 * the load: plant_aniso_ok_at. */
int plant_aniso_ok(const plant_machine_t *m) {
  const double m0 = m->aniso.m0, m2 = m->aniso.m2;
  double k_lo, k_hi;
  star_k_range(&m->aniso, &k_lo, &k_hi);
  if (!(isfinite(m0) && isfinite(m2) && fabs(m->aniso.phi_self) < 10.0 &&
        fabs(m->aniso.phi_mut) < 10.0 && m->aniso.amp_iq >= -0.5 && m->aniso.amp_iq <= 1.0 &&
        k_lo >= STAR_K_MIN && k_lo <= 1.0 && k_hi >= 1.0 && k_hi <= STAR_K_MAX)) {
    return 0;
  }
  const double l0 = 0.5 * (m->ld + m->lq) + m0, l2 = (m->ld - m->lq) - 2.0 * m2;
  if (!(fabs(l2 - m2) > 1e-9 * l0)) {
    return 0;
  }
  if (!star_pd(l0, l2, m0, m2, 1.0, 0.0)) {
    return 0;
  }
  if (fabs(m->aniso.amp_iq) > 0.0) { /* the load scaling's ends */
    return star_pd(l0, l2, m0, m2, k_lo, 0.0) && star_pd(l0, l2, m0, m2, k_hi, 0.0);
  }
  return 1;
}

int plant_aniso_ok_at(const plant_machine_t *m, double i_q) {
  const double m0 = m->aniso.m0, m2 = m->aniso.m2;
  const double l0 = 0.5 * (m->ld + m->lq) + m0, l2 = (m->ld - m->lq) - 2.0 * m2;
  return star_pd(l0, l2, m0, m2, star_k(&m->aniso, i_q),
                 (m->aniso.phi_mut - m->aniso.phi_self) * i_q);
}

/* g = T adj(L) / (T adj(L) T^T): the column sums of the adjugate of the
 * symmetric L, normalised (the determinant cancels). */
static void star_divider(const double L[3][3], double g[3]) {
  double s[3] = {0.0, 0.0, 0.0}, sum = 0.0;
  for (int i = 0; i < 3; i++) {
    const int i1 = (i + 1) % 3, i2 = (i + 2) % 3;
    for (int j = 0; j < 3; j++) {
      const int j1 = (j + 1) % 3, j2 = (j + 2) % 3;
      s[j] += L[i1][j1] * L[i2][j2] - L[i1][j2] * L[i2][j1]; /* cofactor C_ij = adj_ji */
    }
  }
  for (int j = 0; j < 3; j++) {
    sum += s[j];
  }
  for (int j = 0; j < 3; j++) {
    g[j] = s[j] / sum;
  }
}

void plant_star_gain(const plant_t *pl, double theta_e, double i_q, double g[3]) {
  if (!pl->p.machine.aniso.enabled) {
    g[0] = g[1] = g[2] = 1.0 / 3.0;
    return;
  }
  double L[3][3], dL[3][3];
  star_matrix(pl, cos(theta_e), sin(theta_e), i_q, L, dL);
  star_divider(L, g);
}

double plant_star_vn(const plant_t *pl, const double v[3], const double i[3], double c_e,
                     double s_e, double we, double i_q, const double e[3]) {
  if (!pl->p.machine.aniso.enabled) {
    return (v[0] + v[1] + v[2]) * (1.0 / 3.0);
  }
  double L[3][3], dL[3][3], g[3];
  star_matrix(pl, c_e, s_e, i_q, L, dL);
  /* mut: star_point_isotropic */
  star_divider(L, g);
  double vn = 0.0;
  for (int k = 0; k < 3; k++) {
    const double dli = dL[k][0] * i[0] + dL[k][1] * i[1] + dL[k][2] * i[2];
    vn += g[k] * (v[k] - pl->p.machine.rs * i[k] - we * dli - e[k]);
  }
  return vn;
}

void plant_star_filter(plant_t *pl, double v0, double v1, double h) {
  const double tau = pl->p.sensors.star_tau;
  if (!(tau > 0.0) || !(h > 0.0)) {
    pl->aux.star_vf = v1;
    return;
  }
  const double r = h / tau;
  const double e = exp(-r);
  /* exact for v(t) linear from v0 to v1 over h; 1 - e = r - r^2/2 ... for
   * small r */
  const double one_e = r < 1e-6 ? r * (1.0 - 0.5 * r) : 1.0 - e;
  pl->aux.star_vf = v1 + (pl->aux.star_vf - v0) * e - (v1 - v0) * one_e / r;
}

void plant_star_request(plant_t *pl, int n, const double t_req[]) {
  plant_aux_t *a = &pl->aux;
  a->star_n = 0;
  for (int k = 0; k < n && k < PLANT_STAR_MAX; k++) {
    const double t = t_req[k];
    if (t > 0.0 && t < pl->p.ts && (k == 0 || t > a->star_t[k - 1])) {
      a->star_t[a->star_n++] = t;
    }
  }
}

int plant_star_read(plant_t *pl, double v[PLANT_STAR_MAX]) {
  const plant_sensors_t *s = &pl->p.sensors;
  const plant_aux_t *a = &pl->aux;
  if (a->star_n == 0) { /* the usual period: none requested */
    return 0;
  }
  const double fs = s->star_full_scale > 0.0 ? s->star_full_scale : 0.5 * s->v_full_scale;
  const double lsb = 2.0 * fs / a->adc_levels;
  for (int k = 0; k < a->star_n; k++) {
    const double noise = s->star_noise > 0.0 ? s->star_noise * plant_sensors_normal(pl) : 0.0;
    const double raw =
        (1.0 + s->star_gain_error) * (a->star_v[k] - 0.5 * pl->v_dc) + s->star_offset + noise;
    double code = floor(raw / lsb + 0.5) + 0.5 * a->adc_levels;
    code = code < 0.0 ? 0.0 : (code > a->adc_levels - 1.0 ? a->adc_levels - 1.0 : code);
    v[k] = (code - 0.5 * a->adc_levels) * lsb;
  }
  return a->star_n;
}

void plant_aniso_ab(const plant_machine_t *m, double *a, double *b) {
  const double l0 = 0.5 * (m->ld + m->lq) + m->aniso.m0, l2 = (m->ld - m->lq) - 2.0 * m->aniso.m2;
  const double g0 = l0 - m->aniso.m0, g2 = 0.5 * l2 + m->aniso.m2;
  const double k = (l2 - m->aniso.m2) / (3.0 * (g0 * g0 - g2 * g2)); /* (3.7) */
  *a = g0 * k;
  *b = g2 * k;
}

/* (3.7) with the load's L2, M2 as phasors (self terms turned by phi_self
 * i_q, mutual by phi_mut i_q, both scaled by k): the 2theta term carries
 * L2 - M2, the 4theta term (L2/2 + M2)(L2 - M2), so the (3.97) shifts
 * are phi_a = arg(L2 - M2), phi_b = phi_a + arg(L2/2 + M2) (from their
 * unloaded values) and p = b/a = k |L2/2 + M2| / (L0 - M0), with the
 * unloaded sign (checked against the divider's signal,
 * tests/plant/test_star_point.c). */
void plant_aniso_load(const plant_machine_t *m, double i_q, double *phi_a, double *phi_b,
                      double *p) {
  const plant_aniso_t *an = &m->aniso;
  const double l2 = (m->ld - m->lq) - 2.0 * an->m2, m2 = an->m2, g0 = 0.5 * (m->ld + m->lq);
  const double ts = an->phi_self * i_q, tm = an->phi_mut * i_q;
  /* L2 e^{j ts} - M2 e^{j tm} and L2/2 e^{j ts} + M2 e^{j tm} */
  const double ar = l2 * cos(ts) - m2 * cos(tm), ai = l2 * sin(ts) - m2 * sin(tm);
  const double br = 0.5 * l2 * cos(ts) + m2 * cos(tm), bi = 0.5 * l2 * sin(ts) + m2 * sin(tm);
  const double a0 = l2 - m2, b0 = 0.5 * l2 + m2;
  *phi_a = atan2(ai * a0, ar * a0); /* arg of (L2 - M2)(i_q) / (L2 - M2)(0) */
  const double db = b0 != 0.0 ? atan2(bi * b0, br * b0) : 0.0;
  *phi_b = *phi_a + db;
  *p = (b0 < 0.0 ? -1.0 : 1.0) * star_k(an, i_q) * sqrt(br * br + bi * bi) / g0;
}
