#include "acquire/Instrument.h"

#include <algorithm>
#include <cmath>
#include <fmt/format.h>
#include <stdexcept>

namespace ltm::acquire {

namespace {

// The compressive acquisition's random patterns, beside its screening stripes (Instrument.h says
// why 1024).
constexpr int kCompressiveRandom = 1024;

const std::vector<std::pair<Method, std::vector<std::string>>>& channels_by_method() {
    static const std::vector<std::pair<Method, std::vector<std::string>>> table = {
        {Method::Fields, {"BrightField", "DarkField"}},
        {Method::Gray, {"MeanX", "MeanY"}},
        {Method::Stripes, {"ScatterRows", "ScatterColumns"}},
        {Method::Compressive,
         {"ScatterCount", "ScatterWidth", "ScatterDiameter", "EllipseMajor", "EllipseMinor", "EllipseAngle",
          "RobustScatterCount", "RobustScatterDiameter"}},
    };
    return table;
}

AcquireOptions options_for(Method m, int P, int Q) {
    AcquireOptions o;
    o.method = m;
    o.dark_block = automatic_dark_block({Q, P, 0, 0});  // features.exr's DarkField block
    switch (m) {
        case Method::Fields: o.patterns = 2; break;
        case Method::Gray: o.patterns = 2 * (ceil_log2(P) + ceil_log2(Q)) + 6; break;
        case Method::Stripes: o.patterns = P + Q; break;
        case Method::Compressive:
        case Method::BruteForce: {
            const int K = (P + o.stripe_width - 1) / o.stripe_width + (Q + o.stripe_width - 1) / o.stripe_width +
                          kCompressiveRandom;
            if (static_cast<long>(P) * Q <= K) {
                o.method = Method::BruteForce;  // no more patterns than compressive sensing would show
                o.patterns = P * Q;
            } else {
                o.patterns = K;
            }
            break;
        }
    }
    return o;
}

}  // namespace

AcquireOptions instrument_for(const std::string& channel, int P, int Q) {
    for (const auto& [m, names] : channels_by_method())
        if (std::find(names.begin(), names.end(), channel) != names.end()) return options_for(m, P, Q);
    throw std::invalid_argument("instrument_for: no measurement for channel '" + channel + "'");
}

std::string describe(const AcquireOptions& o) { return fmt::format("{} (K = {})", method_name(o.method), o.patterns); }

double measured_resolution(const std::string& channel, const AcquireOptions& o, const SensorModel& sensor,
                           const DisplayGrid& display) {
    const double adc_step = 1.0 / ((std::ldexp(1.0, sensor.camera.bits) - 1) * sensor.camera.exposure);
    Resolution q;
    q.fraction = adc_step;
    const double pitch = std::min(display.width / display.Q, display.height / display.P);
    q.mm = o.period * pitch * adc_step / M_PI;
    q.moment = adc_step;  // a recovered entry's weight resolved to one step moves a moment by about that
    if (o.method == Method::Stripes) q.display_pixels = stripe_width_for(o.patterns, display.P, display.Q);
    return q.of(channel);
}

InstrumentImages measure_features(const CsrMatrix& T, int N, int M, const DisplayGrid& display, const SensorModel& sensor,
                                  int threads) {
    InstrumentImages out;
    out.features.width = N;
    out.features.height = M;
    for (const auto& [m, names] : channels_by_method()) {
        AcquireOptions o = options_for(m, display.P, display.Q);
        o.threads = threads;
        const AcquireResult r = run_acquisition(T, N, M, display, o, sensor);
        for (const std::string& name : names) {
            // The bright field is the one exposure every acquisition takes beside its patterns
            // (AcquireResult::bright): the image `acquire` judges every CNR against.
            const bool bright = name == "BrightField";
            out.features.channels.emplace_back(name, bright ? r.bright.channel(name) : r.features.channel(name));
            out.how[name] = bright ? std::string("bright field (K = 1)") : describe(o);
            out.resolution[name] = measured_resolution(name, o, sensor, display);
        }
    }
    return out;
}

}  // namespace ltm::acquire
