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
 *       swaps sin and cos and sets their signs.
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

/* x -> t (quadrant in the low bits of its representation), r, z = r^2; T their type */
#define RD_SC_REDUCE(T, x, t, r, z)               \
  do {                                            \
    (t) = (x) * RD_SC_TWO_OVER_PI + RD_SC_ROUNDER; \
    const T rd_sc_k = (t) - RD_SC_ROUNDER;        \
    (r) = (x) - rd_sc_k * RD_SC_PIO2_1;           \
    (r) = (r) - rd_sc_k * RD_SC_PIO2_2;           \
    (r) = (r) - rd_sc_k * RD_SC_PIO2_3;           \
    (z) = (r) * (r);                              \
  } while (0)

/* sin r and cos r on |r| <= pi/4: coefficients (-1)^n / m!, summed by Estrin's scheme
   (pairs of terms, then with z^2, then with z^4) rather than Horner's: 4 dependent
   operations instead of 8, and a chain's dynamics starts from these values. */
#define RD_SC_POLY(T, r, z, sp, cp)                                                               \
  do {                                                                                            \
    const T rd_sc_z2 = (z) * (z), rd_sc_z4 = rd_sc_z2 * rd_sc_z2;                                 \
    const T rd_sc_s01 = -1.0 / 6.0 + (z) * (1.0 / 120.0);                                         \
    const T rd_sc_s23 = -1.0 / 5040.0 + (z) * (1.0 / 362880.0);                                   \
    const T rd_sc_s45 = -1.0 / 39916800.0 + (z) * (1.0 / 6227020800.0);                           \
    const T rd_sc_s67 = -1.0 / 1307674368000.0 + (z) * (1.0 / 355687428096000.0);                 \
    const T rd_sc_s = (rd_sc_s01 + rd_sc_z2 * rd_sc_s23) + rd_sc_z4 * (rd_sc_s45 + rd_sc_z2 * rd_sc_s67); \
    const T rd_sc_c01 = 1.0 / 24.0 + (z) * (-1.0 / 720.0);                                        \
    const T rd_sc_c23 = 1.0 / 40320.0 + (z) * (-1.0 / 3628800.0);                                 \
    const T rd_sc_c45 = 1.0 / 479001600.0 + (z) * (-1.0 / 87178291200.0);                         \
    const T rd_sc_c = (rd_sc_c01 + rd_sc_z2 * rd_sc_c23) +                                        \
                      rd_sc_z4 * (rd_sc_c45 + rd_sc_z2 * (1.0 / 20922789888000.0));               \
    (sp) = (r) + ((r) * (z)) * rd_sc_s;                                                           \
    (cp) = (1.0 - 0.5 * (z)) + rd_sc_z2 * rd_sc_c;                                                \
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
   and batched variants. */
#define RD_SC_VECTOR(T, U, x, s, c)                                                      \
  do {                                                                                   \
    T rd_sc_t, rd_sc_r, rd_sc_z, rd_sc_sp, rd_sc_cp;                                     \
    RD_SC_REDUCE(T, x, rd_sc_t, rd_sc_r, rd_sc_z);                                       \
    RD_SC_POLY(T, rd_sc_r, rd_sc_z, rd_sc_sp, rd_sc_cp);                                    \
    U rd_sc_q = (U)rd_sc_t, rd_sc_si = (U)rd_sc_sp, rd_sc_ci = (U)rd_sc_cp;              \
    RD_SC_QUADRANT(U, rd_sc_q, rd_sc_si, rd_sc_ci);                                      \
    (s) = (T)rd_sc_si;                                                                   \
    (c) = (T)rd_sc_ci;                                                                   \
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
