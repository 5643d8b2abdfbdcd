// `ltmsim acquire DIR --method M --patterns K [K ...]`: how well a real system, showing K display
// patterns to a noisy camera instead of measuring T column by column, gets the features of the
// render in DIR (ltm.npz and run.json; reference.exr for the deflection map; regions.json from
// `ltmsim experiment` for the defects' contrast). acquire/ simulates and decodes; this command
// reads, checks, measures against the exact features of T and writes (docs/acquisition.md):
//   OUT/features-K<K>.exr   the estimated feature images, features.exr's channel names
//   OUT/report.json         per K: errors against the exact features, CNR of every defect
//   OUT/plot.png            relative error and CNR against K
// OUT defaults to DIR/acquire-<method>; it appears complete or not at all (io/AtomicFolder.h).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fmt/format.h>
#include <iostream>

#include "acquire/Acquisition.h"
#include "acquire/Instrument.h"
#include "app/Commands.h"
#include "app/FeatureOutputs.h"
#include "app/SceneSetup.h"
#include "app/SensorFile.h"
#include "features/Contrast.h"
#include "features/Plot.h"
#include "io/AtomicFolder.h"
#include "io/Image.h"
#include "io/InputError.h"
#include "io/Json.h"
#include "io/LtmFile.h"
#include "study/Experiment.h"

namespace ltm::app {

namespace fs = std::filesystem;
using io::Json;
using io::json_number;

namespace {

struct AcquireArgs {
    std::string dir, out, method = "gray", sensor, family = "bernoulli";
    std::vector<int> patterns;
    int stripe_width = 8;
    double period = 16, sigmas = 5;
    int threads = 0;
    bool verbose = false, overwrite = false, noise_free = false;
};

// The channel whose CNR the plot shows for a method: the one it is built for.
std::string primary_channel(acquire::Method m, const FeatureImages& f) {
    switch (m) {
        case acquire::Method::Gray: return f.has("Deflection") ? "Deflection" : "MeanX";
        case acquire::Method::Stripes: return "ScatterRows";
        case acquire::Method::Compressive:
        case acquire::Method::BruteForce: return "ScatterCount";
        case acquire::Method::Fields: return "DarkField";
    }
    return "BrightField";
}

// Errors of an estimated channel against the exact one, over the pixels where both are finite.
Json channel_error(const std::vector<float>& est, const std::vector<float>& exact) {
    double se = 0, ae = 0, ref = 0;
    long n = 0, mismatch = 0;
    std::vector<double> abs_err;
    for (std::size_t k = 0; k < est.size(); ++k) {
        const bool fe = std::isfinite(est[k]), fx = std::isfinite(exact[k]);
        if (fe != fx) ++mismatch;
        if (!fe || !fx) continue;
        const double d = static_cast<double>(est[k]) - exact[k];
        se += d * d;
        ae += std::fabs(d);
        abs_err.push_back(std::fabs(d));
        ref += static_cast<double>(exact[k]) * exact[k];
        ++n;
    }
    const double rmse = n ? std::sqrt(se / n) : NAN, rms = n ? std::sqrt(ref / n) : NAN;
    // Quantiles of |error| (nearest rank): the RMS is dominated by a few rows whose energy is
    // spread far (the paper's "white dots"), the median says what a typical pixel gets.
    auto quantile = [&](double f) {
        if (abs_err.empty()) return static_cast<double>(NAN);
        const std::size_t i = std::min(abs_err.size() - 1, static_cast<std::size_t>(f * abs_err.size()));
        std::nth_element(abs_err.begin(), abs_err.begin() + static_cast<std::ptrdiff_t>(i), abs_err.end());
        return abs_err[i];
    };
    return {{"rmse", json_number(rmse)},
            {"mean_abs_error", json_number(n ? ae / n : NAN)},
            {"median_abs_error", json_number(quantile(0.5))},
            {"p95_abs_error", json_number(quantile(0.95))},
            {"exact_rms", json_number(rms)},
            {"relative_rmse", json_number(rms > 0 ? rmse / rms : NAN)},
            {"pixels", n},
            {"finite_mismatch", mismatch}};
}

// The three CNRs of one defect in one channel (docs/acquisition.md, "Which noise"):
//   exact     the exact-T feature's CNR: the contrast table's rendered number, whose noise is the
//             simulator's Monte Carlo noise (the random Fresnel choices), which a real camera
//             does not have;
//   acquired  the estimated feature's CNR with its own surround spread: the sensor's noise, the
//             surround's real structure, and only the Monte Carlo variation the sensor can see
//             (entries below the detection threshold, the single far-off paths, are not
//             measured). The measure the table and `visible` use: judged under the sensor model.
//   sensor    the estimated feature's contrast over the sensor's noise alone: the std over the
//             surround of (estimate - repeat) / sqrt 2, the repeat being the same acquisition with
//             an independent noise seed (same T, same patterns: everything but the sensor's noise
//             cancels). An upper bound: it leaves out the surround's structure, so a decoder whose
//             output the noise never changes (Gray code alone, counts far above the noise) gets
//             the resolution's noise floor whatever its contrast.
// Each is measure_cnr's (study/Experiment.h, the contrast table's), its noise never below the
// image's q / sqrt 12: q_exact that of the rendered image, q that of the measured one. The
// sensor's noise has the same floor: two independent rounding errors of step q differ by
// q / sqrt 6, which over sqrt 2 is q / sqrt 12 again.
struct Cnrs {
    double exact = NAN, acquired = NAN, sensor = NAN;
};

Cnrs cnrs(const std::vector<float>& est, const std::vector<float>& repeat, const std::vector<float>& exact,
          const DefectRegions& g, double q_exact, double q) {
    Cnrs c;
    c.exact = measure_cnr(exact, g, q_exact).cnr;
    const ContrastResult a = measure_cnr(est, g, q);
    c.acquired = a.cnr;
    if (std::isnan(a.defect_mean)) {
        c.sensor = a.cnr;  // not imaged (0) or not measured (NaN)
        return c;
    }
    std::vector<float> diff(est.size());
    for (std::size_t k = 0; k < est.size(); ++k) diff[k] = static_cast<float>((est[k] - repeat[k]) / std::sqrt(2.0));
    // Only the surround's spread is wanted (the defect region may hold NaN rows of the repeat).
    const double noise = measure_cnr(diff, {g.defect, g.kind, g.size, g.surround, g.surround}, q).noise;
    c.sensor = std::isnan(noise) ? NAN : std::fabs(a.defect_mean - a.surround_mean) / noise;
    return c;
}

Json cnr_json(const Cnrs& c) {
    return {{"exact", json_number(c.exact)}, {"acquired", json_number(c.acquired)}, {"sensor", json_number(c.sensor)}};
}

struct KResult {
    int K = 0;
    acquire::AcquireResult r, repeat;  // repeat: an independent noise seed (for the sensor's CNR)
    Json report;
};

int fail(const std::string& message) {
    std::cerr << "ltmsim acquire: " << message << "\n";
    return 2;
}

int run(const AcquireArgs& a) {
    // Everything is read and checked before anything is computed or written.
    const fs::path npz = fs::path(a.dir) / "ltm.npz";
    if (fs::is_regular_file(a.dir))
        return fail(fmt::format("{} is a file, not a render folder; render it first (ltmsim render {} -o DIR) and give "
                                "acquire that folder (ltmsim acquire DIR ...)",
                                a.dir, a.dir));
    if (!fs::exists(a.dir))
        return fail(fmt::format("{}: no such folder (a render folder: ltmsim render SCENE -o {})", a.dir, a.dir));
    if (!fs::is_regular_file(npz))
        return fail(fmt::format("{}: no ltm.npz there (render it with ltmsim render SCENE -o {})", a.dir, a.dir));
    acquire::Method method;
    if (!acquire::parse_method(a.method, method)) return fail(fmt::format("--method {}: unknown method", a.method));
    if (!(a.period > 0) || !std::isfinite(a.period)) return fail(fmt::format("--period must be a finite number > 0 (got {})", a.period));
    if (!(a.sigmas > 0) || !std::isfinite(a.sigmas)) return fail(fmt::format("--sigmas must be a finite number > 0 (got {})", a.sigmas));
    acquire::SensorModel sensor;
    CsrMatrix T;
    RenderGeometry g;
    std::optional<std::vector<float>> reference;
    std::vector<DefectRegions> regions;
    try {
        if (!a.sensor.empty()) sensor = load_sensor_file(a.sensor);
        sensor.noise_free = a.noise_free;
        const std::string bad = acquire::check(sensor);
        if (!bad.empty()) return fail(bad);
        T = read_ltm_npz(npz.string());
        g = read_render_geometry(a.dir);
        if (T.rows != static_cast<std::int64_t>(g.camera_columns) * g.camera_rows ||
            T.cols != static_cast<std::int64_t>(g.display.P) * g.display.Q)
            return fail(fmt::format("{} is {} x {} but run.json describes a {} x {} camera and a {} x {} display", npz.string(),
                                    T.rows, T.cols, g.camera_columns, g.camera_rows, g.display.Q, g.display.P));
        reference = read_reference(a.dir, g.camera_columns * g.camera_rows);
        const fs::path rj = fs::path(a.dir) / "regions.json";
        if (fs::exists(rj)) regions = read_regions_json(rj.string(), static_cast<long>(g.camera_columns) * g.camera_rows);
    } catch (const std::exception& e) {
        return fail(e.what());
    }
    std::vector<int> Ks = a.patterns;
    std::sort(Ks.begin(), Ks.end());
    Ks.erase(std::unique(Ks.begin(), Ks.end()), Ks.end());
    acquire::AcquireOptions o;
    o.method = method;
    o.stripe_width = a.stripe_width;
    o.hadamard = a.family == "hadamard";
    o.period = a.period;
    o.sigmas = a.sigmas;
    o.dark_block = automatic_dark_block(g.display);  // features.exr's DarkField block (write_features)
    o.threads = a.threads;
    for (int K : Ks) {
        o.patterns = K;
        const std::string bad = acquire::check_patterns(o, g.display.P, g.display.Q);
        if (!bad.empty()) return fail(fmt::format("--patterns {}: {}", K, bad));
    }
    const std::string out = a.out.empty() ? (fs::path(a.dir) / fmt::format("acquire-{}", a.method)).string() : a.out;
    if (!output_folder_ok("acquire", out)) return 2;
    if (fs::exists(out) && !a.overwrite) return fail(fmt::format("{} exists; pass --overwrite to replace it", out));

    // The exact features of T (features.exr's, recomputed: the same call write_features makes).
    FeatureOptions fo;
    fo.dark_block = o.dark_block;
    const FeatureImages exact =
        compute_features(T, g.camera_columns, g.camera_rows, g.display, fo, reference ? &*reference : nullptr);

    std::vector<KResult> results;
    for (int K : Ks) {
        o.patterns = K;
        KResult kr;
        kr.K = K;
        kr.r = acquire::run_acquisition(T, g.camera_columns, g.camera_rows, g.display, o, sensor);
        if (!regions.empty()) {
            acquire::SensorModel other = sensor;
            other.seed = acquire::mix64(sensor.seed ^ 0x7265706561740000ULL);  // "repeat"
            kr.repeat = acquire::run_acquisition(T, g.camera_columns, g.camera_rows, g.display, o, other);
        }
        for (FeatureImages* f : {&kr.r.features, &kr.repeat.features})
            if (reference && f->has("MeanX") && f->has("MeanY") && !f->has("Deflection")) add_deflection(*f, *reference);
        const FeatureImages& f = kr.r.features;
        Json errors = Json::object();
        for (const auto& [name, v] : f.channels)
            if (exact.has(name)) errors[name] = channel_error(v, exact.channel(name));
        Json defects = Json::array();
        // The images' resolutions: the rendered one's from the samples per pixel (none where
        // run.json does not give them), the measured one's from the sensor and the method.
        const Resolution rendered = g.samples_per_pixel > 0 ? rendered_resolution(g.samples_per_pixel, g.display) : Resolution{};
        auto q_exact = [&](const std::string& name) { return g.samples_per_pixel > 0 ? rendered.of(name) : 0.0; };
        auto q = [&](const std::string& name) { return acquire::measured_resolution(name, o, sensor, g.display); };
        for (const DefectRegions& d : regions) {
            Json ch = Json::object();
            for (const auto& [name, v] : f.channels)
                if (exact.has(name))
                    ch[name] = cnr_json(
                        cnrs(v, kr.repeat.features.channel(name), exact.channel(name), d, q_exact(name), q(name)));
            defects.push_back({{"defect", d.defect},
                               {"kind", d.kind},
                               {"label", d.describe()},
                               {"size", d.size_json()},
                               {"channels", ch},
                               {"bright_field", cnr_json(cnrs(kr.r.bright.channel("BrightField"),
                                                              kr.repeat.bright.channel("BrightField"),
                                                              exact.channel("BrightField"), d, q_exact("BrightField"),
                                                              q("BrightField")))}});
        }
        kr.report = {{"patterns", K},
                     {"shown", kr.r.summary},
                     {"pattern_seconds", kr.r.pattern_seconds},
                     {"simulate_seconds", kr.r.simulate_seconds},
                     {"decode_seconds", kr.r.decode_seconds},
                     {"errors", errors},
                     {"defects", defects}};
        if (a.verbose)
            std::cerr << fmt::format("acquire {} K = {}: {}; patterns {:.3f} s, simulate {:.3f} s, decode {:.3f} s\n",
                                     a.method, K, kr.r.summary, kr.r.pattern_seconds, kr.r.simulate_seconds,
                                     kr.r.decode_seconds);
        results.push_back(std::move(kr));
    }

    // The fewest patterns (of those run) at which each defect is visible: acquired CNR >= 5.
    Json fewest = Json::array();
    for (std::size_t d = 0; d < regions.size(); ++d) {
        Json ch = Json::object();
        for (const auto& [name, v] : results.front().r.features.channels) {
            if (!exact.has(name)) continue;
            Json k = nullptr;
            for (const KResult& kr : results) {
                const Json& c = kr.report["defects"][d]["channels"][name]["acquired"];
                if (c.is_number() && c.get<double>() >= kVisibleCnr) {
                    k = kr.K;
                    break;
                }
                if (c.is_string() && c.get<std::string>() == "inf") {
                    k = kr.K;
                    break;
                }
            }
            ch[name] = k;
        }
        fewest.push_back({{"defect", regions[d].defect}, {"kind", regions[d].kind}, {"fewest_patterns", ch}});
    }

    const acquire::CameraModel& c = sensor.camera;
    const acquire::DisplayModel& dm = sensor.display;
    Json report = {
        {"dir", a.dir},
        {"method", a.method},
        {"family", method == acquire::Method::Compressive ? Json(a.family) : Json(nullptr)},
        {"camera_pixels", {g.camera_columns, g.camera_rows}},
        {"display_pixels", {g.display.Q, g.display.P}},
        {"sensor",
         {{"noise_free", sensor.noise_free},
          {"seed", sensor.seed},
          {"camera", {{"full_well", c.full_well}, {"exposure", c.exposure}, {"read_noise", c.read_noise},
                      {"dark_level", c.dark_level}, {"bits", c.bits}}},
          {"display", {{"black_level", dm.black_level}, {"gamma", dm.gamma}, {"bits", dm.bits}}}}},
        {"detection_sigmas", a.sigmas},
        {"visible_cnr", kVisibleCnr},
        {"cnr_note", "exact: exact-T feature, Monte Carlo noise (the contrast table's); acquired: estimate over its own "
                     "surround spread (sensor noise, structure, the Monte Carlo variation the sensor sees), the one "
                     "'visible' uses; sensor: estimate's contrast over the sensor noise alone, the std of (estimate - "
                     "repeat) / sqrt 2 in the surround, repeat = the same acquisition with an independent noise seed "
                     "(an upper bound)"},
        {"runs", Json::array()},
        {"visible", fewest}};
    for (const KResult& kr : results) report["runs"].push_back(kr.report);

    // The figure: the median |error| of every channel against K (in the channel's unit: the RMS is
    // ruled by the few rows whose light is spread far, and relative errors mean nothing where the
    // exact image is mostly 0, as the deflection map is), and the primary channel's CNR.
    std::vector<double> xs;
    for (const KResult& kr : results) xs.push_back(kr.K);
    std::vector<Series> err_series;
    const auto& chans = results.front().r.features.channels;
    int ci = 0;
    for (const auto& [name, v] : chans) {
        if (!exact.has(name)) continue;
        Series s;
        s.name = name;
        s.x = xs;
        for (const KResult& kr : results) {
            const Json& e = kr.report["errors"][name]["median_abs_error"];
            s.y.push_back(e.is_number() ? e.get<double>() : NAN);
        }
        s.colour = series_colour(ci++, static_cast<int>(chans.size()));
        err_series.push_back(std::move(s));
    }
    const std::string primary = primary_channel(method, results.front().r.features);
    std::vector<Series> cnr_series;
    for (std::size_t d = 0; d < regions.size(); ++d) {
        const Rgb colour = series_colour(static_cast<int>(d), static_cast<int>(regions.size()));
        Series acq, bright, ex;
        acq.name = fmt::format("defect {} ({}), {}", regions[d].defect, regions[d].describe(), primary);
        bright.name = fmt::format("defect {}, bright field", regions[d].defect);
        ex.name = fmt::format("defect {}, exact T (MC noise)", regions[d].defect);
        bright.dashed = true;
        ex.dotted = true;
        for (const KResult& kr : results) {
            const Json& dj = kr.report["defects"][d];
            auto val = [](const Json& j) { return j.is_number() ? j.get<double>() : NAN; };
            if (dj["channels"].contains(primary)) {
                acq.y.push_back(val(dj["channels"][primary]["acquired"]));
                ex.y.push_back(val(dj["channels"][primary]["exact"]));
            } else {
                acq.y.push_back(NAN);
                ex.y.push_back(NAN);
            }
            bright.y.push_back(val(dj["bright_field"]["acquired"]));
        }
        for (Series* s : {&acq, &bright, &ex}) {
            s->x = xs;
            s->colour = colour;
            cnr_series.push_back(*s);
        }
    }
    const Image plot = montage(
        {{line_plot(err_series, fmt::format("{}: error against the exact features of T", a.method), "patterns K",
                    "median |error| (channel unit)", true, true)},
         {line_plot(cnr_series, fmt::format("{}: defect CNR under the sensor model (acquired)", a.method), "patterns K",
                    "CNR", true, true)}},
        {}, {}, "");

    io::AtomicFolder folder(out, "acquisition folder");
    for (const KResult& kr : results)
        write_exr((fs::path(folder.path()) / fmt::format("features-K{}.exr", kr.K)).string(), kr.r.features.width,
                  kr.r.features.height, kr.r.features.channels);
    io::write_json_file((fs::path(folder.path()) / "report.json").string(), report, "acquisition report");
    write_png((fs::path(folder.path()) / "plot.png").string(), plot);
    folder.commit();
    // One line per K: the error of each channel, relative RMS against the exact feature of T (the
    // report's relative_rmse), and with regions the CNR of each defect in the method's main
    // channel beside the bright field's, both under the sensor (acquired).
    for (const KResult& kr : results) {
        std::string line = fmt::format("K = {} ({}): relative RMS error against the exact features of T:", kr.K, a.method);
        const char* sep = " ";
        for (const auto& [name, e] : kr.report["errors"].items())
            if (e["relative_rmse"].is_number()) {
                line += fmt::format("{}{} {:.3g}", sep, name, e["relative_rmse"].get<double>());
                sep = ", ";
            }
        std::cout << line << "\n";
        for (std::size_t d = 0; d < regions.size(); ++d) {
            const Json& dj = kr.report["defects"][d];
            auto text = [](const Json& j) {
                return j.is_number() ? fmt::format("{:.3g}", j.get<double>()) : j.is_string() ? j.get<std::string>() : "-";
            };
            const std::string main = dj["channels"].contains(primary) ? text(dj["channels"][primary]["acquired"]) : "-";
            std::cout << fmt::format("  defect {} ({}): CNR under the sensor: {} {}, bright field {}\n", regions[d].defect,
                                     regions[d].describe(), primary, main, text(dj["bright_field"]["acquired"]));
        }
    }
    return 0;
}

}  // namespace

void add_acquire_command(CLI::App& app) {
    auto args = std::make_shared<AcquireArgs>();
    CLI::App* cmd = app.add_subcommand("acquire", "Simulate a physical acquisition of DIR's features with K display patterns");
    cmd->add_option("dir", args->dir, "A folder written by ltmsim render (ltm.npz, run.json)")->required();
    cmd->add_option("--method", args->method, "gray | stripes | compressive | brute-force | fields (default gray)")
        ->check(CLI::IsMember({"gray", "stripes", "compressive", "brute-force", "fields"}));
    cmd->add_option("--patterns", args->patterns, "The number of patterns K; several values run a sweep")->required()->expected(1, 64);
    cmd->add_option("--sensor", args->sensor, "A YAML file with a sensor section (default: the documented camera and LCD)");
    cmd->add_option("--family", args->family, "compressive: bernoulli | hadamard (default bernoulli)")
        ->check(CLI::IsMember({"bernoulli", "hadamard"}));
    cmd->add_option("--stripe-width", args->stripe_width, "compressive: width of the screening stripes (default 8)");
    cmd->add_option("--period", args->period, "gray: phase-shift period in display pixels (default 16)");
    cmd->add_option("--sigmas", args->sigmas, "Detection threshold in noise standard deviations (default 5)");
    cmd->add_option("-o,--output", args->out, "Output folder (default DIR/acquire-METHOD)");
    add_threads_option(cmd, args->threads, "Threads (default: all cores)");
    cmd->add_flag("--noise-free", args->noise_free, "No camera noise or quantisation: the decoders' own error");
    cmd->add_flag("--verbose", args->verbose, "Print each K's simulation and decoding time");
    cmd->add_flag("--overwrite", args->overwrite, "Replace an existing output folder");
    cmd->callback([args] { run_guarded("acquire", args->threads, [&] { return run(*args); }); });
}

}  // namespace ltm::app
