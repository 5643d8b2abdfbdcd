#include "acquire/Patterns.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <unordered_set>

#include "acquire/CounterRng.h"

namespace ltm::acquire {

namespace {

PatternBlock empty_block(int P, int Q, int K, bool binary) {
    PatternBlock b;
    b.P = P;
    b.Q = Q;
    b.K = K;
    b.binary = binary;
    b.words = binary ? (K + 63) / 64 : 0;
    return b;
}

}  // namespace

PatternBlock PatternBlock::make_binary(int P, int Q, int K) {
    PatternBlock b = empty_block(P, Q, K, true);
    b.bits.assign(static_cast<std::size_t>(b.pixels()) * b.words, 0);
    return b;
}

PatternBlock PatternBlock::make_grey(int P, int Q, int K) {
    PatternBlock b = empty_block(P, Q, K, false);
    b.values.assign(static_cast<std::size_t>(b.pixels()) * K, 0.0f);
    return b;
}

int ceil_log2(int n) {
    int b = 0;
    while ((1LL << b) < n) ++b;
    return b;
}

namespace {

int gray(int v) { return v ^ (v >> 1); }

int from_gray(int g) {
    int v = 0;
    for (; g; g >>= 1) v ^= g;
    return v;
}

}  // namespace

PatternBlock gray_code_block(int P, int Q) {
    const int nq = ceil_log2(Q), np = ceil_log2(P);
    PatternBlock b = PatternBlock::make_binary(P, Q, 2 * (nq + np));
    for (int p = 0; p < P; ++p)
        for (int q = 0; q < Q; ++q) {
            const long l = static_cast<long>(p) * Q + q;
            for (int i = 0; i < nq; ++i) b.set(l, 2 * i + (((gray(q) >> (nq - 1 - i)) & 1) ? 0 : 1));
            for (int i = 0; i < np; ++i) b.set(l, 2 * (nq + i) + (((gray(p) >> (np - 1 - i)) & 1) ? 0 : 1));
        }
    return b;
}

PatternBlock phase_block(int P, int Q, int steps, double period, const DisplayModel& display) {
    PatternBlock b = PatternBlock::make_grey(P, Q, 2 * steps);
    for (int p = 0; p < P; ++p)
        for (int q = 0; q < Q; ++q) {
            float* v = &b.values[(static_cast<std::size_t>(p) * Q + q) * b.K];
            for (int j = 0; j < steps; ++j) {
                const double d = 2 * M_PI * j / steps;
                v[j] = static_cast<float>(linear_command(display, 0.5 * (1 + std::cos(2 * M_PI * q / period - d))));
                v[steps + j] = static_cast<float>(linear_command(display, 0.5 * (1 + std::cos(2 * M_PI * p / period - d))));
            }
        }
    return b;
}

PatternBlock stripe_block(int P, int Q, int width) {
    const int nc = (Q + width - 1) / width, nr = (P + width - 1) / width;
    PatternBlock b = PatternBlock::make_binary(P, Q, nc + nr);
    for (int p = 0; p < P; ++p)
        for (int q = 0; q < Q; ++q) {
            const long l = static_cast<long>(p) * Q + q;
            b.set(l, q / width);
            b.set(l, nc + p / width);
        }
    return b;
}

PatternBlock bernoulli_block(int P, int Q, int K, std::uint64_t seed) {
    PatternBlock b = PatternBlock::make_binary(P, Q, K);
    // One 64-bit draw of stream (seed, word, pixel) gives 64 patterns' bits of one pixel.
    for (long l = 0; l < b.pixels(); ++l)
        for (int w = 0; w < b.words; ++w) {
            std::uint64_t r = CounterRng(seed, static_cast<std::uint64_t>(w), static_cast<std::uint64_t>(l)).next();
            if (w == b.words - 1 && K % 64) r &= (std::uint64_t(1) << (K % 64)) - 1;
            b.bits[static_cast<std::size_t>(l) * b.words + w] = r;
        }
    return b;
}

PatternBlock hadamard_block(int P, int Q, int K, std::uint64_t seed) {
    const long n = static_cast<long>(P) * Q;
    const int order_log = ceil_log2(static_cast<int>(n));
    const std::uint64_t order = std::uint64_t(1) << order_log;
    if (static_cast<std::uint64_t>(K) > order - 1)
        throw std::invalid_argument("hadamard_block: more patterns than non-constant Hadamard rows");
    std::vector<std::uint64_t> rows;
    std::unordered_set<std::uint64_t> taken;
    CounterRng rng(seed, 0x4861646dULL, 0);
    while (static_cast<int>(rows.size()) < K) {
        const std::uint64_t r = 1 + rng.next() % (order - 1);
        if (taken.insert(r).second) rows.push_back(r);
    }
    PatternBlock b = PatternBlock::make_binary(P, Q, K);
    for (long l = 0; l < n; ++l)
        for (int j = 0; j < K; ++j)
            if (__builtin_popcountll(rows[static_cast<std::size_t>(j)] & static_cast<std::uint64_t>(l)) % 2 == 0) b.set(l, j);
    return b;
}

PatternBlock field_block(int P, int Q, int dark_block) {
    PatternBlock b = PatternBlock::make_binary(P, Q, 2);
    const int p0 = P / 2 - dark_block / 2, q0 = Q / 2 - dark_block / 2;
    for (int p = 0; p < P; ++p)
        for (int q = 0; q < Q; ++q) {
            const long l = static_cast<long>(p) * Q + q;
            b.set(l, 0);
            if (!(p >= p0 && p < p0 + dark_block && q >= q0 && q < q0 + dark_block)) b.set(l, 1);
        }
    return b;
}

// ---- decoders ----

namespace {

// Decoded channels as camera-sized feature images.
FeatureImages images(int columns, int rows, std::vector<std::pair<std::string, std::vector<float>>> channels) {
    FeatureImages f;
    f.width = columns;
    f.height = rows;
    f.channels = std::move(channels);
    return f;
}

// Wraps d into [-period/2, period/2).
double wrap(double d, double period) {
    d = std::fmod(d + period / 2, period);
    if (d < 0) d += period;
    return d - period / 2;
}

}  // namespace

FeatureImages decode_mean_position(const Measurements& gray, const Measurements* phase, int camera_columns,
                                   int camera_rows, const DisplayGrid& display, int steps, double period,
                                   const SensorModel& sensor, double sigmas) {
    const int nq = ceil_log2(display.Q), np = ceil_log2(display.P);
    if (gray.K != 2 * (nq + np)) throw std::invalid_argument("decode_mean_position: the Gray code images do not match the display");
    if (phase && phase->K != 2 * steps) throw std::invalid_argument("decode_mean_position: the phase images do not match the steps");
    const long pixels = static_cast<long>(camera_columns) * camera_rows;
    const double b = sensor.display.black_level;
    std::vector<float> mx(static_cast<std::size_t>(pixels)), my(static_cast<std::size_t>(pixels));
    for (long k = 0; k < pixels; ++k) {
        // Row sum: every pair sums to (1 + b) s.
        double sum = 0;
        for (int j = 0; j < gray.K; ++j) sum += gray.at(k, j);
        const int pairs = gray.K / 2;
        const double s = sum / (pairs * (1 + b));
        // Each pair's sum has variance 2 var(y) at y ~ (1 + b) s / 2 (the pattern and inverse each
        // near half of it when the row is split, or s and b s when not: the larger bound is used).
        const double sd = std::sqrt(2 * measurement_variance(sensor, s) / pairs) / (1 + b);
        if (pairs == 0 || !(s > sigmas * sd) || (sensor.noise_free && !(s > 0))) {
            mx[static_cast<std::size_t>(k)] = my[static_cast<std::size_t>(k)] = NAN;
            continue;
        }
        auto axis = [&](int first_pair, int nbits, int n, int phase_offset) {
            int g = 0;
            for (int i = 0; i < nbits; ++i) {
                const int bit = gray.at(k, 2 * (first_pair + i)) > gray.at(k, 2 * (first_pair + i) + 1) ? 1 : 0;
                g = (g << 1) | bit;
            }
            const int c = std::min(from_gray(g), n - 1);
            if (!phase || steps == 0) return static_cast<double>(c);
            double re = 0, im = 0;
            for (int j = 0; j < steps; ++j) {
                const double d = 2 * M_PI * j / steps;
                const double v = phase->at(k, phase_offset + j);
                re += v * std::cos(d);
                im += v * std::sin(d);
            }
            const double frac = std::atan2(im, re) * period / (2 * M_PI);
            return c + wrap(frac - c, period);
        };
        const double q = axis(0, nq, display.Q, 0), p = axis(nq, np, display.P, steps);
        mx[static_cast<std::size_t>(k)] = static_cast<float>(-display.width / 2 + (q + 0.5) * display.width / display.Q);
        my[static_cast<std::size_t>(k)] = static_cast<float>(display.height / 2 - (p + 0.5) * display.height / display.P);
    }
    return images(camera_columns, camera_rows, {{"MeanX", std::move(mx)}, {"MeanY", std::move(my)}});
}

StripeSupport stripe_support(const Measurements& y, long pixel, int P, int Q, int width, const SensorModel& sensor,
                             double sigmas) {
    const int nc = (Q + width - 1) / width, nr = (P + width - 1) / width;
    const double b = sensor.display.black_level;
    StripeSupport out;
    auto axis = [&](int first, int n, std::vector<int>& lit) {
        double sum = 0;
        for (int i = 0; i < n; ++i) sum += y.at(pixel, first + i);
        const double s = sum / (n * b + 1 - b);
        const double var_s = n * measurement_variance(sensor, b * s) / ((n * b + 1 - b) * (n * b + 1 - b));
        for (int i = 0; i < n; ++i) {
            const double yi = y.at(pixel, first + i);
            const double m = (yi - b * s) / (1 - b);
            const double sd = std::sqrt(measurement_variance(sensor, yi) + b * b * var_s) / (1 - b);
            // Noise-free: m is exact up to the rounding of n-term double sums (~n 2^-53 s), so any
            // marginal above 1e-9 s is light; below it, rounding.
            if (sensor.noise_free ? m > 1e-9 * s : m > sigmas * sd) lit.push_back(i);
        }
        return s;
    };
    out.row_sum = axis(0, nc, out.columns);
    axis(nc, nr, out.rows);
    return out;
}

FeatureImages decode_stripes(const Measurements& y, int camera_columns, int camera_rows, const DisplayGrid& display,
                             int width, const SensorModel& sensor, double sigmas) {
    const long pixels = static_cast<long>(camera_columns) * camera_rows;
    std::vector<float> rows(static_cast<std::size_t>(pixels)), cols(rows.size()), sw(rows.size());
    for (long k = 0; k < pixels; ++k) {
        const StripeSupport s = stripe_support(y, k, display.P, display.Q, width, sensor, sigmas);
        const double dc = s.columns.empty() ? 0.0 : static_cast<double>(s.columns.back() - s.columns.front()) * width;
        const double dr = s.rows.empty() ? 0.0 : static_cast<double>(s.rows.back() - s.rows.front()) * width;
        cols[static_cast<std::size_t>(k)] = static_cast<float>(dc);
        rows[static_cast<std::size_t>(k)] = static_cast<float>(dr);
        sw[static_cast<std::size_t>(k)] = static_cast<float>(dr * display.Q + dc);
    }
    return images(camera_columns, camera_rows,
                  {{"ScatterWidth", std::move(sw)}, {"ScatterRows", std::move(rows)}, {"ScatterColumns", std::move(cols)}});
}

FeatureImages decode_fields(const Measurements& y, int camera_columns, int camera_rows) {
    const long pixels = static_cast<long>(camera_columns) * camera_rows;
    std::vector<float> bright(static_cast<std::size_t>(pixels)), dark(bright.size());
    for (long k = 0; k < pixels; ++k) {
        bright[static_cast<std::size_t>(k)] = static_cast<float>(y.at(k, 0));
        dark[static_cast<std::size_t>(k)] = static_cast<float>(y.at(k, 1));
    }
    return images(camera_columns, camera_rows, {{"BrightField", std::move(bright)}, {"DarkField", std::move(dark)}});
}

}  // namespace ltm::acquire
