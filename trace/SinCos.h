#pragma once
// The cosine and sine of the angle 2 pi u, for the camera's azimuth (u a uniform draw): one
// function whose every operation a SIMD lane repeats (lanes::cos_sin_turns, trace/Lanes.h), so a
// camera sample is the same bits whether it is computed alone or in a packet. The C library's
// sin and cos have no vector twin with their bits, and cost 8 % of a render (perf, one thread,
// paper scene at 1024 spp, mesh-only).
//
// The maths, for any u with |4 u| < 2^51 (the camera's u lie in [0, 1)):
//  1. Quarter turns, exactly. q = 4 u is exact (a power of two). k = q rounded to the nearest
//     integer by adding and subtracting 1.5 * 2^52 (round to nearest: the sum's ulp is 1). The
//     remainder r = q - k, |r| <= 1/2, is exact: for k = 0 it is q; otherwise q and k lie within a
//     factor of two of each other (Sterbenz's lemma). So 2 pi u = (pi / 2) k + (pi / 2) r with no
//     error so far, and the quarter turns k mod 4 only swap and negate cosine and sine.
//  2. The reduced angle x = (pi / 2) r, |x| <= pi / 4, rounded once: the product and pi / 2's own
//     rounding move x by at most 2 eps |x| (eps = 2^-53).
//  3. sin x and cos x on [-pi / 4, pi / 4] by the polynomials of fdlibm's __kernel_sin and
//     __kernel_cos (Sun Microsystems, 1993: "Permission to use, copy, modify, and distribute this
//     software is freely granted, provided that this notice is preserved"): minimax in z = x^2,
//     approximation error below 2^-58, evaluated as fdlibm does (cos as w + ((1 - w) - z/2 +
//     z r) with w = 1 - z/2, so that the leading term is exact), under an ulp each.
//  So each result is within 1 ulp of the true value at x plus |x| 2 eps <= 1.6 eps from step 2:
//  within 3 eps of cos(2 pi u) and sin(2 pi u) in absolute terms (tests/Tolerances.h,
//  turn_cos_sin; tests/trace_optics.cpp checks it against long double).
// Bit for bit: only + - * and the sign, with no fused multiply-adds (-ffp-contract=off): the same
// operations in the lane twin give the same bits on every instruction set.
#include <cstdint>
#include <cstring>

namespace ltm {

namespace sincos_detail {
// pi / 2 rounded to double.
inline constexpr double kHalfPi = 1.57079632679489661923;
// Adding then subtracting 1.5 * 2^52 rounds a double of magnitude below 2^51 to an integer.
inline constexpr double kRoundInteger = 6755399441055744.0;
// fdlibm k_sin.c: sin x = x + x^3 (S1 + z (S2 + ... + z S6)).
inline constexpr double S1 = -1.66666666666666324348e-01, S2 = 8.33333333332248946124e-03,
                        S3 = -1.98412698298579493134e-04, S4 = 2.75573137070700676789e-06,
                        S5 = -2.50507602534068634195e-08, S6 = 1.58969099521155010221e-10;
// fdlibm k_cos.c: cos x = 1 - z/2 + z^2 (C1 + z (C2 + ... + z C6)).
inline constexpr double C1 = 4.16666666666666019037e-02, C2 = -1.38888888888741095749e-03,
                        C3 = 2.48015872894767294178e-05, C4 = -2.75573143513906633035e-07,
                        C5 = 2.08757232129817482790e-09, C6 = -1.13596475577881948265e-11;
}  // namespace sincos_detail

struct CosSin {
    double cos = 1, sin = 0;
};

// cos(2 pi u) and sin(2 pi u), each within 3 eps (above). Not finite u gives NaN.
inline CosSin cos_sin_turns(double u) {
    using namespace sincos_detail;
    const double q = 4.0 * u;
    const double shifted = q + kRoundInteger;
    const double k = shifted - kRoundInteger;
    const double x = (q - k) * kHalfPi;
    const double z = x * x;
    const double sr = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    const double s = x + z * x * (S1 + z * sr);
    const double cr = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    const double hz = 0.5 * z, w = 1.0 - hz;
    const double c = w + (((1.0 - w) - hz) + z * cr);
    // k mod 4 from the low bits of the shifted sum (its ulp is 1, and 2^51 is a multiple of 4).
    std::uint64_t bits;
    std::memcpy(&bits, &shifted, sizeof bits);
    const unsigned quarter = static_cast<unsigned>(bits & 3u);
    const double a = (quarter & 1u) ? s : c, b = (quarter & 1u) ? c : s;
    return {((quarter + 1u) & 2u) ? -a : a, (quarter & 2u) ? -b : b};
}

}  // namespace ltm
