/* sin and cos of one argument, as generated code and the interpreter compute them.
 *
 * Nearly every trigonometric value of a robot function is sin and cos of a joint
 * angle. libm's sincos is a call (about 9 ns here; in a batched chunk one per lane),
 * and a call clobbers every register. This kernel is inline and branch-free for
 * |x| <= 2^19, so the batched code runs it in all SIMD lanes at once:
 *
 *   k = nearest integer to x * 2/pi (added to 1.5 * 2^52, whose low mantissa bits are
 *       then k mod 4: the quadrant), r = x - k pi/2 with pi/2 in three parts (Cody and
 *       Waite: the first two have 33 significant bits, so k times them is exact for
 *       |k| < 2^20), then Taylor polynomials on |r| <= pi/4 (sin to r^17, cos to r^16:
 *       truncation below 1e-17 relative, under a tenth of an ulp), and the quadrant
 *       swaps sin and cos and sets their signs. z = r^2 is computed beside the third
 *       part's subtraction, not after it: (r2 - e)^2 = r2^2 - 2 e r2 + e^2 with
 *       e = k pi/2's third part under 2^-50, r2 the reduction after two parts (and r2 in
 *       the middle term as r1, the reduction after one: they differ by under 2^-14).
 *
 * Within 2 ulp of libm (tests/codegen/sincos_kernel_test.cpp; sin(-0) is +0). Larger or
 * non-finite arguments go to libm's sincos. Pure C99, also compiled as C++: the
 * interpreter includes this file, so compiled and interpreted functions agree bit for
 * bit where the compiler contracts nothing into FMAs.
 *
 * The reduction and the polynomials are macros over any arithmetic type, so the SIMD
 * variants of the generated code (GNU vector extensions: RD_SC_VECTOR) run the same
 * operations.
 */
#ifndef ROBODIFF_CODEGEN_SINCOS_KERNEL_H
#define ROBODIFF_CODEGEN_SINCOS_KERNEL_H

#ifndef RD_LIBC_DECLARED /* generated C declares sincos, fabs and memcpy itself */
#include <math.h>
#include <string.h>
#endif
#include <stdint.h>

#define RD_SC_TWO_OVER_PI 0x1.45f306dc9c883p-1
#define RD_SC_ROUNDER 0x1.8p52
#define RD_SC_PIO2_1 0x1.921fb544p+0
#define RD_SC_PIO2_2 0x1.0b4611a6p-34
#define RD_SC_PIO2_3 0x1.3198a2e037073p-69
#define RD_SC_LIMIT 0x1p19
#define RD_SC_LIMIT_BITS 0x4120000000000000ULL /* the bits of 2^19 */
#define RD_SC_SIGN_BIT 0x8000000000000000ULL

/* x -> t (quadrant in the low bits of its representation), r, z = r^2; T their type.
   z is r2^2 + w (one fused multiply-add; w, the square's correction for the third part,
   is ready as soon as r2), so it does not wait for r. */
#define RD_SC_REDUCE(T, x, t, r, z)                              \
  do {                                                           \
    (t) = (x) * RD_SC_TWO_OVER_PI + RD_SC_ROUNDER;                \
    const T rd_sc_k = (t) - RD_SC_ROUNDER;                       \
    const T rd_sc_r1 = (x) - rd_sc_k * RD_SC_PIO2_1;             \
    const T rd_sc_r2 = rd_sc_r1 - rd_sc_k * RD_SC_PIO2_2;        \
    const T rd_sc_square = rd_sc_r2 * rd_sc_r2;                  \
    const T rd_sc_w = (rd_sc_k * (-2.0 * RD_SC_PIO2_3)) * rd_sc_r1; \
    (z) = rd_sc_square + rd_sc_w;                                \
    (r) = rd_sc_r2 - rd_sc_k * RD_SC_PIO2_3;                     \
  } while (0)

/* sin r = r + r z S(z) and cos r = (1 - z/2) + z^2 C(z) on |r| <= pi/4: S and C have the
   coefficients (-1)^n / m!, summed by Estrin's scheme (pairs of terms, then with z^2, then
   with z^4) rather than Horner's: 4 dependent operations instead of 8, and a chain's
   dynamics starts from these values. RD_SC_TAILS: z^2, S(z) and C(z). */
#define RD_SC_TAILS(T, z, z2, st, ct)                                                             \
  do {                                                                                            \
    (z2) = (z) * (z);                                                                             \
    const T rd_sc_z4 = (z2) * (z2);                                                               \
    const T rd_sc_s01 = -1.0 / 6.0 + (z) * (1.0 / 120.0);                                         \
    const T rd_sc_s23 = -1.0 / 5040.0 + (z) * (1.0 / 362880.0);                                   \
    const T rd_sc_s45 = -1.0 / 39916800.0 + (z) * (1.0 / 6227020800.0);                           \
    const T rd_sc_s67 = -1.0 / 1307674368000.0 + (z) * (1.0 / 355687428096000.0);                 \
    (st) = (rd_sc_s01 + (z2) * rd_sc_s23) + rd_sc_z4 * (rd_sc_s45 + (z2) * rd_sc_s67);             \
    const T rd_sc_c01 = 1.0 / 24.0 + (z) * (-1.0 / 720.0);                                        \
    const T rd_sc_c23 = 1.0 / 40320.0 + (z) * (-1.0 / 3628800.0);                                 \
    const T rd_sc_c45 = 1.0 / 479001600.0 + (z) * (-1.0 / 87178291200.0);                         \
    (ct) = (rd_sc_c01 + (z2) * rd_sc_c23) + rd_sc_z4 * (rd_sc_c45 + (z2) * (1.0 / 20922789888000.0)); \
  } while (0)

#define RD_SC_POLY(T, r, z, sp, cp)                   \
  do {                                                \
    T rd_sc_z2, rd_sc_st, rd_sc_ct;                   \
    RD_SC_TAILS(T, z, rd_sc_z2, rd_sc_st, rd_sc_ct);  \
    (sp) = (r) + ((r) * (z)) * rd_sc_st;              \
    (cp) = (1.0 - 0.5 * (z)) + rd_sc_z2 * rd_sc_ct;   \
  } while (0)

/* From the bits of t, sp, cp to those of sin x and cos x: an odd quadrant swaps them;
   sin is negative in quadrants 2 and 3, cos in 1 and 2. U: the type of the bits. */
#define RD_SC_QUADRANT(U, q, si, ci)                            \
  do {                                                          \
    const U rd_sc_swap = -((q) & 1);                            \
    const U rd_sc_s = ((si) & ~rd_sc_swap) | ((ci) & rd_sc_swap); \
    const U rd_sc_c = ((ci) & ~rd_sc_swap) | ((si) & rd_sc_swap); \
    (si) = rd_sc_s ^ (((q) & 2) << 62);                         \
    (ci) = rd_sc_c ^ ((((q) + 1) & 2) << 62);                   \
  } while (0)

/* The kernel on a GNU vector of doubles T (U: a vector of as many uint64s) in every lane
   at once, no range check: s and c are lvalues of type T. Generated code's pair, quad
   and batched variants. The quadrant's signs are set before the polynomials' last
   operations, so only the swap comes after them: sin r ends in cos x in odd quadrants
   and in sin x in even ones, so it takes cos x's sign (negative in quadrants 1 and 2) on
   its leading term and factor r; cos r takes sin x's (2 and 3) on 1 - z/2 and z^2. */
#define RD_SC_VECTOR(T, U, x, s, c)                                                          \
  do {                                                                                       \
    T rd_sc_t, rd_sc_r, rd_sc_z, rd_sc_z2, rd_sc_st, rd_sc_ct;                               \
    RD_SC_REDUCE(T, x, rd_sc_t, rd_sc_r, rd_sc_z);                                           \
    RD_SC_TAILS(T, rd_sc_z, rd_sc_z2, rd_sc_st, rd_sc_ct);                                   \
    const U rd_sc_q = (U)rd_sc_t, rd_sc_swap = -(rd_sc_q & 1);                               \
    const U rd_sc_sin_r_sign = ((rd_sc_q + 1) & 2) << 62, rd_sc_cos_r_sign = (rd_sc_q & 2) << 62; \
    const T rd_sc_rs = (T)((U)rd_sc_r ^ rd_sc_sin_r_sign);                                   \
    const T rd_sc_sp = rd_sc_rs + (rd_sc_rs * rd_sc_z) * rd_sc_st;                           \
    const T rd_sc_cp = (T)((U)(1.0 - 0.5 * rd_sc_z) ^ rd_sc_cos_r_sign) +                    \
                       (T)((U)rd_sc_z2 ^ rd_sc_cos_r_sign) * rd_sc_ct;                       \
    (s) = (T)(((U)rd_sc_sp & ~rd_sc_swap) | ((U)rd_sc_cp & rd_sc_swap));                     \
    (c) = (T)(((U)rd_sc_cp & ~rd_sc_swap) | ((U)rd_sc_sp & rd_sc_swap));                     \
  } while (0)

/* The kernel on one argument with |x| <= 2^19 (not checked): generated code whose
   every argument is checked at its entry (docs/code-generation.md). */
static inline void rd_sincos1_in_range(double x, double* s, double* c) {
  double t, r, z, sp, cp;
  uint64_t q, si, ci;
  RD_SC_REDUCE(double, x, t, r, z);
  RD_SC_POLY(double, r, z, sp, cp);
  memcpy(&q, &t, sizeof q);
  memcpy(&si, &sp, sizeof si);
  memcpy(&ci, &cp, sizeof ci);
  RD_SC_QUADRANT(uint64_t, q, si, ci);
  memcpy(s, &si, sizeof si);
  memcpy(c, &ci, sizeof ci);
}

static inline void rd_sincos1(double x, double* s, double* c) {
  if (!(fabs(x) <= RD_SC_LIMIT)) {
    sincos(x, s, c);
    return;
  }
  rd_sincos1_in_range(x, s, c);
}

#endif
