#pragma once
// A simulated physical acquisition: K display patterns shown one after the other, K camera images
// y_j = T L(x_j) taken through the sensor model (acquire/Sensor.h), and the decoder of the
// pattern family (acquire/Patterns.h, acquire/Recovery.h) that turns them into feature images
// with the channel names of features.exr (features/Features.h).
//
// Simulating K patterns is one sparse product over all of them at once, Y = T X with X the
// PQ x K pattern block (bit-packed for binary families), parallel over T's rows (TBB): each row's
// K sums are accumulated in double in T's column order by one task, and its noise comes from the
// counter-based streams (seed, pattern, camera pixel), so Y is bit-identical for any thread count.
#include <cstdint>
#include <string>
#include <vector>

#include "acquire/Patterns.h"
#include "acquire/Sensor.h"
#include "features/Features.h"
#include "io/CsrMatrix.h"

namespace ltm::acquire {

// The radiances y_j = T L(x_j) of every camera pixel (no noise) when noise_free, else their
// calibrated measurements; pattern j of the block draws its noise from stream (seed,
// first_pattern + j, k), so blocks of one acquisition never share a stream. threads = 0: all
// cores. T must be valid with T.cols == X.P X.Q (std::invalid_argument otherwise).
Measurements simulate(const CsrMatrix& T, const PatternBlock& X, const SensorModel& sensor, std::uint64_t first_pattern,
                      int threads);

// The pattern index whose noise streams the bright field beside every acquisition draws from
// (AcquireResult::bright): one no method shows (theirs count from 0 to K - 1 < 2^31), the same
// for every method and K, so that the reference a CNR is judged against is one image whatever
// the method.
inline constexpr std::uint64_t kBrightFieldPattern = std::uint64_t{1} << 62;

enum class Method { Gray, Stripes, Compressive, BruteForce, Fields };

// The method's name on the command line ("gray", "stripes", "compressive", "brute-force",
// "fields") and back (false for an unknown name).
const char* method_name(Method m);
bool parse_method(const std::string& name, Method& m);

struct AcquireOptions {
    Method method = Method::Gray;
    int patterns = 0;              // K, the patterns shown in all
    int stripe_width = 8;          // compressive: width of the screening stripes (display pixels)
    bool hadamard = false;         // compressive: Hadamard rows instead of Bernoulli patterns
    double period = 16;            // gray: phase-shift period (display pixels)
    double sigmas = 5;             // detection threshold, in standard deviations of the noise
    int dark_block = 60;           // fields: features/Features.h's DarkField block
    std::uint64_t pattern_seed = 1;  // compressive: the random patterns (the noise has the sensor's seed)
    int threads = 0;
};

// What the method needs: "" if K = options.patterns fits a P x Q display, else one sentence
// saying why not, with the valid counts near K. Rules (docs/acquisition.md):
//   gray         2 (ceil log2 P + ceil log2 Q) + 2 s, s = 0 or s >= 3 phase steps per axis
//   stripes      ceil(P / w) + ceil(Q / w) for a stripe width w >= 1 (w is chosen from K)
//   compressive  ceil(P / w) + ceil(Q / w) screening stripes (w = stripe_width) + at least 8
//                random patterns, at most P Q in all
//   brute-force  P Q (one display pixel at a time)
//   fields       2 (bright field and dark field)
// and always 1 <= K <= P Q.
std::string check_patterns(const AcquireOptions& options, int P, int Q);

// The stripe width stripes uses for K patterns (the smallest w with ceil(P/w) + ceil(Q/w) <= K).
int stripe_width_for(int K, int P, int Q);

struct AcquireResult {
    FeatureImages features;  // the method's estimates, features.exr's channel names
    FeatureImages bright;    // a bright field through the same sensor (one more image, not counted in K;
                             // its noise from kBrightFieldPattern's streams)
    std::string summary;     // what was shown: "36 Gray code + 8 phase-shift patterns (period 16 px)"
    // Wall-clock times: drawing the pattern blocks, the product Y = T X with the sensor's noise,
    // and the decoder (for brute-force, simulating is streamed inside the decoder's pass).
    double pattern_seconds = 0, simulate_seconds = 0, decode_seconds = 0;
};

// Runs the acquisition and its decoder. Throws std::invalid_argument with check_patterns's
// message (or check(sensor)'s) on bad options.
AcquireResult run_acquisition(const CsrMatrix& T, int camera_columns, int camera_rows, const DisplayGrid& display,
                              const AcquireOptions& options, const SensorModel& sensor);

}  // namespace ltm::acquire
