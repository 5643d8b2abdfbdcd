#include "acquire/Acquisition.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

#include "acquire/Recovery.h"
#include "features/BlockProduct.h"

namespace ltm::acquire {

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

// Runs body in an arena of `threads` threads (0: all cores).
template <class F>
void in_arena(int threads, const F& body) {
    tbb::task_arena arena(threads > 0 ? threads : tbb::task_arena::automatic);
    arena.execute(body);
}

// The random patterns' own seed (not the noise's: a system shows the same patterns every time).
std::uint64_t pattern_seed(const AcquireOptions& o) { return stream_key(o.pattern_seed, 0x7061747465726e73ULL, 1); }

// A compressive row whose screening leaves more candidates than this is not recovered (its
// features are NaN): the dictionary would be K x n with n beyond what a per-row OMP can afford
// (n K doubles). Only rows whose energy reaches far across the display get there.
constexpr long kMaxCandidates = 16384;

}  // namespace

Measurements simulate(const CsrMatrix& T, const PatternBlock& X, const SensorModel& sensor, std::uint64_t first_pattern,
                      int threads) {
    if (T.cols != X.pixels()) throw std::invalid_argument("simulate: the patterns do not cover T's display pixels");
    const int K = X.K;  // T itself is checked by the block product
    const double b = sensor.display.black_level;
    Measurements y;
    y.pixels = T.rows;
    y.K = K;
    // The noise-free radiances, one pass over T for the whole block (features/BlockProduct.h).
    // A binary pattern's radiance is b + (1 - b) [on]: the product sums the lit entries only and
    // b times the row sum is added below. A grey block is multiplied by the radiance of every
    // command value, tabulated once.
    if (X.binary) {
        y.values = multiply_block_binary(T, X.bits, X.words, K, threads);
    } else {
        std::vector<double> radiance(X.values.size());
        for (std::size_t i = 0; i < X.values.size(); ++i) radiance[i] = display_radiance(sensor.display, X.values[i]);
        y.values = multiply_block(T, radiance, K, threads);
    }
    // The measurements, in place: each (pattern, pixel) draws from its own stream.
    in_arena(threads, [&] {
        tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, T.rows, 16), [&](const tbb::blocked_range<std::int64_t>& r) {
            for (std::int64_t k = r.begin(); k != r.end(); ++k) {
                double row_sum = 0;
                if (X.binary)
                    for (std::int64_t i = T.indptr[k]; i < T.indptr[k + 1]; ++i) row_sum += T.data[i];
                double* out = &y.values[static_cast<std::size_t>(k) * K];
                for (int j = 0; j < K; ++j) {
                    const double radiance_kj = X.binary ? b * row_sum + (1 - b) * out[j] : out[j];
                    CounterRng rng(sensor.seed, first_pattern + static_cast<std::uint64_t>(j), static_cast<std::uint64_t>(k));
                    out[j] = measure(sensor, radiance_kj, rng);
                }
            }
        });
    });
    return y;
}

const char* method_name(Method m) {
    switch (m) {
        case Method::Gray: return "gray";
        case Method::Stripes: return "stripes";
        case Method::Compressive: return "compressive";
        case Method::BruteForce: return "brute-force";
        case Method::Fields: return "fields";
    }
    return "?";
}

bool parse_method(const std::string& name, Method& m) {
    for (Method c : {Method::Gray, Method::Stripes, Method::Compressive, Method::BruteForce, Method::Fields})
        if (name == method_name(c)) {
            m = c;
            return true;
        }
    return false;
}

namespace {

int stripes_count(int w, int P, int Q) { return (P + w - 1) / w + (Q + w - 1) / w; }

}  // namespace

int stripe_width_for(int K, int P, int Q) {
    for (int w = 1; w <= std::max(P, Q); ++w)
        if (stripes_count(w, P, Q) <= K) return w;
    return std::max(P, Q);
}

std::string check_patterns(const AcquireOptions& o, int P, int Q) {
    const long PQ = static_cast<long>(P) * Q;
    const int K = o.patterns;
    const std::string display = fmt::format("a {} x {} display", Q, P);
    if (K < 1 || K > PQ) return fmt::format("--patterns must be in [1, {}] for {} (got {})", PQ, display, K);
    switch (o.method) {
        case Method::Gray: {
            const int base = 2 * (ceil_log2(P) + ceil_log2(Q));
            const int extra = K - base;
            if (extra == 0 || (extra >= 6 && extra % 2 == 0)) return "";
            return fmt::format("method gray needs 2 (ceil log2 P + ceil log2 Q) = {} Gray code patterns for {}, plus 2 s "
                               "phase-shift patterns with s >= 3 steps per axis: K = {}, {}, {}, {}, ... (got {})",
                               base, display, base, base + 6, base + 8, base + 10, K);
        }
        case Method::Stripes: {
            const int w = stripe_width_for(K, P, Q);
            if (stripes_count(w, P, Q) == K) return "";
            // The counts nearest K: the largest below (width w) and the smallest above (width
            // w - 1 shows it), each with the width run_acquisition uses for that count,
            // stripe_width_for's: the narrowest stripes that show it. Several widths show one
            // count (166 down to 125 all give 8 patterns for 500 x 500), and 8 patterns mean 125.
            const int below = stripes_count(w, P, Q);
            const int above = w > 1 ? stripes_count(w - 1, P, Q) : below;
            return fmt::format("method stripes shows ceil(P / w) + ceil(Q / w) patterns for {} (w the stripe width): {} "
                               "is not such a count; the nearest are {} (w = {}) and {} (w = {})",
                               display, K, below, w, above, stripe_width_for(above, P, Q));
        }
        case Method::Compressive: {
            if (o.stripe_width < 1) return fmt::format("--stripe-width must be >= 1 (got {})", o.stripe_width);
            const int screen = stripes_count(o.stripe_width, P, Q);
            if (K < screen + 8)
                return fmt::format("method compressive shows {} screening stripes (width {}) for {} and at least 8 random "
                                   "patterns: K >= {} (got {}); a wider --stripe-width needs fewer",
                                   screen, o.stripe_width, display, screen + 8, K);
            if (o.hadamard && K - screen > (1L << ceil_log2(static_cast<int>(PQ))) - 1)
                return fmt::format("too many Hadamard patterns for {}", display);
            return "";
        }
        case Method::BruteForce:
            if (K == PQ) return "";
            return fmt::format("method brute-force shows one display pixel at a time: K = P Q = {} for {} (got {})", PQ,
                               display, K);
        case Method::Fields:
            if (K == 2) return "";
            return fmt::format("method fields shows the bright and the dark field: K = 2 (got {})", K);
    }
    return "unknown method";
}

namespace {

FeatureImages nan_rows(FeatureImages f, const std::vector<char>& bad) {
    for (auto& [name, v] : f.channels)
        for (std::size_t k = 0; k < bad.size(); ++k)
            if (bad[k]) v[k] = NAN;
    return f;
}

// One recovered row: its entries (display pixel, value), columns increasing.
struct RowEntries {
    std::vector<std::pair<std::int32_t, float>> entries;
    bool recovered = true;
};

CsrMatrix to_csr(const std::vector<RowEntries>& rows, std::int64_t cols) {
    CsrMatrix T;
    T.rows = static_cast<std::int64_t>(rows.size());
    T.cols = cols;
    T.indptr.assign(rows.size() + 1, 0);
    for (std::size_t k = 0; k < rows.size(); ++k) {
        for (const auto& [l, v] : rows[k].entries) {
            T.indices.push_back(l);
            T.data.push_back(v);
        }
        T.indptr[k + 1] = static_cast<std::int64_t>(T.data.size());
    }
    return T;
}

// Compressive recovery (docs/acquisition.md): screening stripes give the candidate display pixels
// of each row (T >= 0, so an entry can only sit where both its column stripe and its row stripe
// hold energy: exact without noise), the random patterns give z = A t on them, OMP recovers t.
std::vector<RowEntries> recover_compressive(const Measurements& stripes, const Measurements& random,
                                            const PatternBlock& X, int P, int Q, const AcquireOptions& o,
                                            const SensorModel& sensor) {
    const int K = random.K, w = o.stripe_width;
    const double b = sensor.display.black_level;
    std::vector<double> mean_on(static_cast<std::size_t>(X.pixels()));
    for (long l = 0; l < X.pixels(); ++l) {
        int c = 0;
        for (int word = 0; word < X.words; ++word) c += __builtin_popcountll(X.bits[static_cast<std::size_t>(l) * X.words + word]);
        mean_on[static_cast<std::size_t>(l)] = static_cast<double>(c) / K;
    }
    std::vector<RowEntries> rows(static_cast<std::size_t>(random.pixels));
    in_arena(o.threads, [&] {
        tbb::parallel_for(tbb::blocked_range<long>(0, random.pixels, 4), [&](const tbb::blocked_range<long>& r) {
            for (long k = r.begin(); k != r.end(); ++k) {
                RowEntries& out = rows[static_cast<std::size_t>(k)];
                const StripeSupport s = stripe_support(stripes, k, P, Q, w, sensor, o.sigmas);
                std::vector<std::int32_t> cand;
                const long n_est = static_cast<long>(s.rows.size()) * w * static_cast<long>(s.columns.size()) * w;
                if (n_est > kMaxCandidates) {
                    out.recovered = false;
                    continue;
                }
                for (int rs : s.rows)
                    for (int p = rs * w; p < std::min(P, (rs + 1) * w); ++p)
                        for (int cs : s.columns)
                            for (int q = cs * w; q < std::min(Q, (cs + 1) * w); ++q) cand.push_back(p * Q + q);
                std::sort(cand.begin(), cand.end());
                if (cand.empty()) continue;
                const int n = static_cast<int>(cand.size());
                // z_j = (y_j - mean y) / (1 - b) = sum_l t_l (x_jl - mean_j x_jl): the row sum and the
                // black level drop out.
                double ybar = 0;
                for (int j = 0; j < K; ++j) ybar += random.at(k, j);
                ybar /= K;
                std::vector<double> z(static_cast<std::size_t>(K)), A(static_cast<std::size_t>(K) * n);
                double var_sum = 0, var2_sum = 0;
                for (int j = 0; j < K; ++j) {
                    z[static_cast<std::size_t>(j)] = (random.at(k, j) - ybar) / (1 - b);
                    const double v = measurement_variance(sensor, random.at(k, j)) / ((1 - b) * (1 - b));
                    var_sum += v;
                    var2_sum += v * v;
                }
                for (int i = 0; i < n; ++i)
                    for (int j = 0; j < K; ++j)
                        A[static_cast<std::size_t>(i) * K + j] = (X.on(cand[static_cast<std::size_t>(i)], j) ? 1.0 : 0.0) -
                                                                 mean_on[static_cast<std::size_t>(cand[static_cast<std::size_t>(i)])];
                // Plain OMP (largest |correlation|): the algorithm Tropp's guarantee is about
                // (Recovery.h); T >= 0 is used afterwards, negative coefficients are dropped.
                OmpOptions oo;
                oo.max_atoms = std::max(1, K / 2);
                double znorm = 0;
                for (double v : z) znorm += v * v;
                // Stop where the residual is what the noise explains: its chi-square mean plus
                // `sigmas` of its standard deviations; noise-free, at the rounding level.
                oo.residual_squared = sensor.noise_free ? 1e-20 * znorm : var_sum + o.sigmas * std::sqrt(2 * var2_sum);
                const OmpResult res = omp(A, K, n, z, oo);
                // A coefficient's noise: sigma_z / |a_i| with |a_i|^2 ~ K / 4 for balanced patterns.
                const double coef_sd = std::sqrt(var_sum / K) / std::sqrt(K / 4.0);
                for (std::size_t i = 0; i < res.support.size(); ++i) {
                    const double v = res.values[i];
                    if (v > 0 && (sensor.noise_free || v > o.sigmas * coef_sd))
                        out.entries.emplace_back(cand[static_cast<std::size_t>(res.support[i])], static_cast<float>(v));
                }
                std::sort(out.entries.begin(), out.entries.end());
            }
        });
    });
    return rows;
}

// Brute force: the entry estimate t_hat = (y_hat - b s) / (1 - b) above which a display pixel the
// row does not see turns up, for all n of a row together, with probability at most
// kFalseEntriesPerRow. A dark measurement is S + R electrons, S ~ Poisson(L), L = fe b s + dark,
// R ~ N(0, r^2), so P(S + R > e) = sum_k P(S = k) Q((e - k) / r) (the step function for r = 0);
// e is bisected for n P = kFalseEntriesPerRow and widened by half an ADC step (the rounding to DN).
// Its Poisson tail is what a Gaussian sigma misses: for L ~ 6 and r = 2.4, 5 sigma (17 e- above
// the mean) is exceeded with probability 2.3e-6 (a Gaussian 2.9e-7), 0.58 false entries per row of
// 250 000; the cut for 0.01 lies at 6.0 sigma.
constexpr double kFalseEntriesPerRow = 0.01;

double dark_tail_cut(const SensorModel& sensor, double y_dark, long n) {
    const CameraModel& c = sensor.camera;
    const double fe = c.full_well * c.exposure, L = fe * y_dark + c.dark_level;
    std::vector<double> pmf;
    for (double p = std::exp(-L), k = 0; k < 100000 && (k < L || p > 1e-300); ++k, p *= L / k) pmf.push_back(p);
    auto tail = [&](double e) {
        double t = 0;
        for (std::size_t k = 0; k < pmf.size(); ++k) {
            const double d = e - static_cast<double>(k);
            t += pmf[k] * (c.read_noise > 0 ? 0.5 * std::erfc(d / (c.read_noise * std::sqrt(2.0))) : (d < 0 ? 1.0 : 0.0));
        }
        return t;
    };
    double lo = L, hi = L + 10 * std::sqrt(L + c.read_noise * c.read_noise) + 100;
    while (n * tail(hi) > kFalseEntriesPerRow) hi *= 2;
    for (int i = 0; i < 60; ++i) {
        const double mid = 0.5 * (lo + hi);
        (n * tail(mid) > kFalseEntriesPerRow ? lo : hi) = mid;
    }
    const double e_cut = hi + 0.5 * adc_gain(c);
    // y_hat = (e - dark) / fe, t_hat = (y_hat - b s) / (1 - b).
    return ((e_cut - c.dark_level) / fe - y_dark) / (1 - sensor.display.black_level);
}

// Brute force: display pixel l alone is on in pattern l, so y_l = b s + (1 - b) T[k, l]; every
// one of the P Q measurements of a row is taken (streamed per row, not stored as images), s is
// estimated from their sum (n b + 1 - b) s, and an entry is kept where its estimate exceeds
// `sigmas` standard deviations of a dark measurement.
std::vector<RowEntries> brute_force(const CsrMatrix& T, const AcquireOptions& o, const SensorModel& sensor) {
    const double b = sensor.display.black_level;
    const long n = T.cols;
    std::vector<RowEntries> rows(static_cast<std::size_t>(T.rows));
    in_arena(o.threads, [&] {
        tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, T.rows, 1), [&](const tbb::blocked_range<std::int64_t>& r) {
            std::vector<double> yhat(static_cast<std::size_t>(n));
            for (std::int64_t k = r.begin(); k != r.end(); ++k) {
                double s = 0;
                for (std::int64_t i = T.indptr[k]; i < T.indptr[k + 1]; ++i) s += T.data[i];
                std::int64_t i = T.indptr[k];
                double sum = 0;
                // Every display pixel the row does not see gives the same radiance b s: its signal
                // law is tabulated once per row (the same draws measure() makes).
                const double y_dark = b * s;
                const PoissonLaw dark(sensor.camera.full_well * sensor.camera.exposure * y_dark + sensor.camera.dark_level);
                for (long l = 0; l < n; ++l) {
                    double t = 0;
                    if (i < T.indptr[k + 1] && T.indices[i] == l) t = T.data[i++];
                    CounterRng rng(sensor.seed, static_cast<std::uint64_t>(l), static_cast<std::uint64_t>(k));
                    const double y = b * s + (1 - b) * t;
                    yhat[static_cast<std::size_t>(l)] =
                        sensor.noise_free ? y : (t == 0 ? measure(sensor, dark, rng) : measure(sensor, y, rng));
                    sum += yhat[static_cast<std::size_t>(l)];
                }
                const double s_hat = sum / (n * b + 1 - b);
                const double sd = std::sqrt(measurement_variance(sensor, b * s_hat)) / (1 - b);
                // The threshold is also held above the dark law's own tail: n tests per row at a
                // Gaussian 5 sigma let the heavier Poisson tail through.
                const double cut = std::max(o.sigmas * sd, dark_tail_cut(sensor, b * s_hat, n));
                RowEntries& out = rows[static_cast<std::size_t>(k)];
                for (long l = 0; l < n; ++l) {
                    const double t_hat = (yhat[static_cast<std::size_t>(l)] - b * s_hat) / (1 - b);
                    if (sensor.noise_free ? t_hat > 0 : t_hat > cut)
                        out.entries.emplace_back(static_cast<std::int32_t>(l), static_cast<float>(t_hat));
                }
            }
        });
    });
    return rows;
}

}  // namespace

AcquireResult run_acquisition(const CsrMatrix& T, int N, int M, const DisplayGrid& display, const AcquireOptions& o,
                              const SensorModel& sensor) {
    const std::string bad_sensor = check(sensor);
    if (!bad_sensor.empty()) throw std::invalid_argument(bad_sensor);
    const std::string bad = check_patterns(o, display.P, display.Q);
    if (!bad.empty()) throw std::invalid_argument(bad);
    if (T.rows != static_cast<std::int64_t>(N) * M || T.cols != static_cast<std::int64_t>(display.P) * display.Q)
        throw std::invalid_argument("acquire: T does not match the camera and display");
    const int P = display.P, Q = display.Q;
    AcquireResult out;
    FeatureOptions fo;
    fo.dark_block = std::min(o.dark_block, std::min(P, Q));
    Clock::time_point t0 = Clock::now();
    double decode = 0, patterns = 0;
    auto timed = [](double& sum, auto&& f) {
        const Clock::time_point d0 = Clock::now();
        auto r = f();
        sum += seconds_since(d0);
        return r;
    };
    auto decode_timed = [&](auto&& f) { return timed(decode, f); };
    auto make = [&](auto&& f) { return timed(patterns, f); };
    switch (o.method) {
        case Method::Gray: {
            const int base = 2 * (ceil_log2(P) + ceil_log2(Q));
            const int steps = (o.patterns - base) / 2;
            const Measurements g = simulate(T, make([&] { return gray_code_block(P, Q); }), sensor, 0, o.threads);
            Measurements ph;
            if (steps > 0)
                ph = simulate(T, make([&] { return phase_block(P, Q, steps, o.period, sensor.display); }), sensor, base,
                              o.threads);
            out.features = decode_timed([&] {
                return decode_mean_position(g, steps > 0 ? &ph : nullptr, N, M, display, steps, o.period, sensor, o.sigmas);
            });
            out.summary = steps > 0 ? fmt::format("{} Gray code (pattern + inverse) and {} phase-shift patterns ({} steps "
                                                  "per axis, period {:g} display pixels)",
                                                  base, 2 * steps, steps, o.period)
                                    : fmt::format("{} Gray code patterns (pattern + inverse)", base);
            break;
        }
        case Method::Stripes: {
            const int w = stripe_width_for(o.patterns, P, Q);
            const Measurements y = simulate(T, make([&] { return stripe_block(P, Q, w); }), sensor, 0, o.threads);
            out.features = decode_timed([&] { return decode_stripes(y, N, M, display, w, sensor, o.sigmas); });
            out.summary = fmt::format("{} column and {} row stripes, {} display pixel{} wide", (Q + w - 1) / w,
                                      (P + w - 1) / w, w, w == 1 ? "" : "s");
            break;
        }
        case Method::Compressive: {
            const int w = o.stripe_width;
            const int screen = stripes_count(w, P, Q);
            const int Kc = o.patterns - screen;
            const Measurements s = simulate(T, make([&] { return stripe_block(P, Q, w); }), sensor, 0, o.threads);
            const PatternBlock X = make([&] {
                return o.hadamard ? hadamard_block(P, Q, Kc, pattern_seed(o)) : bernoulli_block(P, Q, Kc, pattern_seed(o));
            });
            const Measurements y = simulate(T, X, sensor, screen, o.threads);
            out.features = decode_timed([&] {
                const std::vector<RowEntries> rows = recover_compressive(s, y, X, P, Q, o, sensor);
                std::vector<char> lost(rows.size());
                for (std::size_t k = 0; k < rows.size(); ++k) lost[k] = !rows[k].recovered;
                return nan_rows(compute_features(to_csr(rows, T.cols), N, M, display, fo), lost);
            });
            out.summary = fmt::format("{} screening stripes ({} display pixels wide) and {} {} patterns, OMP per camera "
                                      "pixel",
                                      screen, w, Kc, o.hadamard ? "Hadamard" : "Bernoulli");
            break;
        }
        case Method::BruteForce: {
            // Simulation and decoding are one streamed pass here (the P Q images are never stored).
            const std::vector<RowEntries> rows = brute_force(T, o, sensor);
            out.features = decode_timed([&] { return compute_features(to_csr(rows, T.cols), N, M, display, fo); });
            out.summary = fmt::format("{} single-pixel patterns", static_cast<long>(P) * Q);
            break;
        }
        case Method::Fields: {
            const Measurements y = simulate(T, make([&] { return field_block(P, Q, fo.dark_block); }), sensor, 0, o.threads);
            out.features = decode_timed([&] { return decode_fields(y, N, M); });
            out.summary = fmt::format("bright field and dark field (centred dark block of {} display pixels)", fo.dark_block);
            break;
        }
    }
    out.decode_seconds = decode;
    out.pattern_seconds = patterns;
    out.simulate_seconds = seconds_since(t0) - decode - patterns;
    // The bright field beside every method: one more image through the same sensor, with streams
    // of its own that no method's patterns use, so it is the same image for every method and K.
    PatternBlock white = PatternBlock::make_binary(P, Q, 1);
    for (long l = 0; l < white.pixels(); ++l) white.set(l, 0);
    const Measurements bf = simulate(T, white, sensor, kBrightFieldPattern, o.threads);
    out.bright.width = N;
    out.bright.height = M;
    out.bright.channels.emplace_back("BrightField", std::vector<float>(bf.values.begin(), bf.values.end()));
    return out;
}

}  // namespace ltm::acquire
