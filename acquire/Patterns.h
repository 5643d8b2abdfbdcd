#pragma once
// Display pattern families and their decoders: what a real inspection system shows on its display
// and how it turns the K camera images y_j = T L(x_j) + noise back into features of T's rows
// (docs/acquisition.md has the derivations, pattern counts and measured accuracy).
//
// Indices as everywhere (docs/conventions.md): display pixel (p, q), l = p Q + q, row p from the
// top; camera pixel k = m N + n. A pattern is a command value per display pixel in [0, 1]; the
// display model (acquire/Sensor.h) turns it into radiance L = b + (1 - b) v^gamma.
//
// Families (pattern counts for a P x Q display, with nq = ceil(log2 Q), np = ceil(log2 P)):
//   gray_code_block     2 (nq + np): the reflected binary Gray code of q and of p, most
//                       significant bit first, each bit as pattern + inverse (columns first).
//   phase_block         2 s: s-step phase shifting along q, then along p, sinusoids of period
//                       `period` display pixels, linear in radiance (drawn through
//                       linear_command): x_j(q) = (1 + cos(2 pi q / period - 2 pi j / s)) / 2.
//   stripe_block        ceil(Q / w) + ceil(P / w): column stripe i lights q in [i w, (i + 1) w),
//                       then row stripe i lights p in [i w, (i + 1) w); w = 1 is a line scan.
//   bernoulli_block     K: every display pixel on with probability 1/2, independently per
//                       pattern (a counter-based hash of (seed, pattern, pixel)).
//   hadamard_block      K: rows r_1..r_K of the Sylvester-Hadamard matrix of order
//                       2^ceil(log2 PQ), distinct, drawn from 1 .. 2^n - 1 by the seed (row 0 is
//                       the all-on pattern); pixel l is on where H[r, l] = (-1)^popcount(r & l) = +1.
//   field_block         2: all on (the bright field), and the dark field's pattern (all on but a
//                       centred dark block, features/Features.h's DarkField geometry).
#include <cstdint>
#include <string>
#include <vector>

#include "acquire/Sensor.h"
#include "features/Features.h"

namespace ltm::acquire {

// K patterns over a P x Q display, stored per display pixel (a PQ x K block, the layout the
// simulation's product T X walks: the K values of one display pixel are contiguous).
struct PatternBlock {
    int P = 0, Q = 0, K = 0;
    bool binary = true;
    int words = 0;                    // binary: 64-bit words per display pixel, ceil(K / 64)
    std::vector<std::uint64_t> bits;  // binary: bit j % 64 of bits[l * words + j / 64]: pattern j on at l
    std::vector<float> values;        // grey: values[l * K + j], the command value of pattern j at l

    static PatternBlock make_binary(int P, int Q, int K);
    static PatternBlock make_grey(int P, int Q, int K);
    long pixels() const { return static_cast<long>(P) * Q; }
    bool on(long l, int j) const { return (bits[static_cast<std::size_t>(l) * words + j / 64] >> (j % 64)) & 1u; }
    void set(long l, int j) { bits[static_cast<std::size_t>(l) * words + j / 64] |= std::uint64_t(1) << (j % 64); }
    float value(long l, int j) const { return binary ? (on(l, j) ? 1.0f : 0.0f) : values[static_cast<std::size_t>(l) * K + j]; }
};

int ceil_log2(int n);  // the smallest b with 2^b >= n (0 for n <= 1)

PatternBlock gray_code_block(int P, int Q);
PatternBlock phase_block(int P, int Q, int steps, double period, const DisplayModel& display);
PatternBlock stripe_block(int P, int Q, int width);
PatternBlock bernoulli_block(int P, int Q, int K, std::uint64_t seed);
PatternBlock hadamard_block(int P, int Q, int K, std::uint64_t seed);
PatternBlock field_block(int P, int Q, int dark_block);

// Camera images: K calibrated measurements y_hat per camera pixel, values[k * K + j].
struct Measurements {
    long pixels = 0;
    int K = 0;
    std::vector<double> values;
    double at(long k, int j) const { return values[static_cast<std::size_t>(k) * K + j]; }
};

// ---- decoders ----

// The mean display position of every camera pixel from Gray code (+ inverse) images and,
// optionally (steps > 0), phase-shift images (phase_block with the same steps and period).
// Per axis (q shown): bit i is 1 where y+ > y- (pattern brighter than its inverse: most of the
// row's energy is on the pattern's lit pixels); the Gray word gives the integer column g (the
// display pixel holding the majority of the energy; clamped to Q - 1). The phase
//     phi = atan2(sum_j y_j sin d_j, sum_j y_j cos d_j),  d_j = 2 pi j / s,
// is arg(sum_l T[k, l] e^(i 2 pi q_l / period)) exactly (the constant part of the sinusoids and
// the display's black level cancel over s >= 3 equal steps), i.e. 2 pi / period times the row's
// energy-weighted mean q for any row whose energy lies within half a period; it is unwrapped
// around g: q_mean = g + wrap(phi period / (2 pi) - g) with wrap into [-period/2, period/2).
// Without phase images q_mean = g. MeanX, MeanY in mm (features/Features.h's display coordinates);
// NaN where the row sum estimate (y+ + y-) / (1 + b), averaged over all pairs, is below
// `sigmas` standard deviations of its noise (no light reaches the pixel).
FeatureImages decode_mean_position(const Measurements& gray, const Measurements* phase, int camera_columns,
                                   int camera_rows, const DisplayGrid& display, int steps, double period,
                                   const SensorModel& sensor, double sigmas);

// What stripe images say about each row: which column stripes and row stripes hold energy.
// A stripe's marginal m_i = (y_i - b s) / (1 - b), s = sum_i y_i / (n b + 1 - b) over the axis's n
// stripes (every display pixel is in exactly one stripe); it holds energy where m_i > sigmas x its
// standard deviation (from the sensor model at the measured level).
struct StripeSupport {
    std::vector<int> columns, rows;  // lit stripe indices, increasing
    double row_sum = 0;              // s from the column stripes
};
StripeSupport stripe_support(const Measurements& y, long pixel, int P, int Q, int width, const SensorModel& sensor,
                             double sigmas);

// ScatterColumns = (last - first lit column stripe) w, ScatterRows likewise (exact for w = 1 and
// entries above the noise; with w > 1 the true extent is within w - 1 of it), and the separable
// bound on ScatterWidth: the first entry is at or after p_min Q + q_min and the last at or before
// p_max Q + q_max, so ScatterWidth <= ScatterRows Q + ScatterColumns (the channel holds this upper
// bound; ScatterRows Q - ScatterColumns is a lower one when ScatterRows > 0).
FeatureImages decode_stripes(const Measurements& y, int camera_columns, int camera_rows, const DisplayGrid& display,
                             int width, const SensorModel& sensor, double sigmas);

// BrightField and DarkField from field_block images: the calibrated measurements themselves.
FeatureImages decode_fields(const Measurements& y, int camera_columns, int camera_rows);

}  // namespace ltm::acquire
