// Dataset specs, their distributions and the samples drawn from them (study/DatasetSpec.h,
// study/Distribution.h, study/Sampler.h), and COCO's run-length encoding (study/Coco.h).
// Statistical checks are z-tests and a chi-square test on seeded draws, at the family level
// tol::kFamilyAlpha split over the checks of this file (Bonferroni).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <fmt/format.h>
#include <map>
#include <random>
#include <unistd.h>

#include "defects/DefectSolid.h"
#include "io/InputError.h"
#include "io/Json.h"
#include "scene/SceneJson.h"
#include "scene/SceneLoader.h"
#include "study/Coco.h"
#include "study/DatasetCard.h"
#include "study/DatasetSpec.h"
#include "study/GoodnessOfFit.h"
#include "study/Sampler.h"
#include "tests/BuildPaths.h"
#include "tests/Tolerances.h"

using namespace ltm;

namespace {

constexpr int kChecks = 14;
const double kZ = tol::normal_two_sided_quantile(tol::kFamilyAlpha / kChecks);

const char* kScene = R"(  object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}
  camera: {resolution: [24, 24], size: [25.0, 25.0], numerical_aperture: 0.01, samples_per_pixel: 16}
  display: {resolution: [60, 60], size: [100.0, 100.0], z: 60.0}
)";

std::string spec_text(const std::string& rest) { return std::string("scene:\n") + kScene + rest; }

// The message of the InputError parsing `text` throws ("" if none).
std::string error_of(const std::string& text) {
    try {
        parse_dataset_spec(text, "spec.yaml");
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

double z_of(double mean, double mu, double var, long n) { return (mean - mu) / std::sqrt(var / static_cast<double>(n)); }

// The InputError that drawing sample i throws (the test fails if there is none).
InputError draw_error(const DatasetSpec& s, long i) {
    try {
        draw_sample(s, i);
    } catch (const InputError& e) {
        return e;
    }
    ADD_FAILURE() << "no error drawing sample " << i;
    return InputError("", 0, 0, "", "no error");
}

}  // namespace

// ---- distributions ----

TEST(Distributions, DrawsFollowTheirLaws) {
    Rng rng(1, 2);
    const long n = 40000;
    // uniform [2, 5]: mean 3.5, variance 9/12; log-uniform [0.1, 10]: log10 uniform on [-1, 1];
    // normal (3, 0.5).
    const Distribution u{Distribution::Kind::Uniform, 2, 5}, lu{Distribution::Kind::LogUniform, 0.1, 10},
        nm{Distribution::Kind::Normal, 3, 0.5};
    double su = 0, sl = 0, sn = 0, sn2 = 0;
    for (long i = 0; i < n; ++i) {
        const double a = u.draw(rng), b = lu.draw(rng), c = nm.draw(rng);
        ASSERT_GE(a, 2);
        ASSERT_LE(a, 5);
        ASSERT_GE(b, 0.1);
        ASSERT_LE(b, 10);
        su += a;
        sl += std::log10(b);
        sn += c;
        sn2 += (c - 3) * (c - 3);
    }
    EXPECT_LT(std::fabs(z_of(su / n, 3.5, 9.0 / 12, n)), kZ);
    EXPECT_LT(std::fabs(z_of(sl / n, 0.0, 4.0 / 12, n)), kZ);
    EXPECT_LT(std::fabs(z_of(sn / n, 3.0, 0.25, n)), kZ);
    // The sample variance of a normal: (x - mu)^2 has mean sd^2 and variance 2 sd^4.
    EXPECT_LT(std::fabs(z_of(sn2 / n, 0.25, 2 * 0.0625, n)), kZ);
}

TEST(Distributions, CountsFollowTheirLaws) {
    Rng rng(3, 4);
    const long n = 40000;
    // Poisson(2.5): mean and variance 2.5. uniform_int [1, 4]: chi-square over its 4 values.
    const CountDistribution p{CountDistribution::Kind::Poisson, 0, 0, 2.5}, ui{CountDistribution::Kind::UniformInt, 1, 4, 0};
    double s = 0, s2 = 0;
    std::map<int, long> hist;
    for (long i = 0; i < n; ++i) {
        const int k = p.draw(rng);
        s += k;
        s2 += (k - 2.5) * (k - 2.5);
        ++hist[ui.draw(rng)];
    }
    EXPECT_LT(std::fabs(z_of(s / n, 2.5, 2.5, n)), kZ);
    // (k - mu)^2 of a Poisson: mean mu, variance mu + 2 mu^2 (its fourth central moment mu + 3 mu^2).
    EXPECT_LT(std::fabs(z_of(s2 / n, 2.5, 2.5 + 2 * 6.25, n)), kZ);
    double chi2 = 0;
    ASSERT_EQ(hist.size(), 4u);
    for (const auto& [k, c] : hist) {
        ASSERT_GE(k, 1);
        ASSERT_LE(k, 4);
        chi2 += (c - n / 4.0) * (c - n / 4.0) / (n / 4.0);
    }
    // 3 degrees of freedom: P(chi2 > 27.9) = 4e-6 < alpha / checks.
    EXPECT_LT(chi2, 27.9);
}

// ---- the spec file ----

TEST(DatasetSpec, ReadsEveryKey) {
    const DatasetSpec s = parse_dataset_spec(spec_text(R"(samples: 12
seed: 7
defect_free_fraction: 0.25
defects:
  - {type: bubble, count: {poisson: 1.5}, radius: {log_uniform: [0.05, 0.3]}}
  - {type: bubble, count: 1, semi_axes: [0.2, {uniform: [0.1, 0.2]}, 0.1], surface_breaking: true, surface: front}
  - {type: scratch, count: {uniform_int: [0, 2]}, surface: {choice: [front, back]}, shape: arc, width: 0.05, depth: 0.02,
     length: {uniform: [1, 3]}, arc_radius: 4, profile: {choice: [V, U]}}
  - {type: particle}
  - {type: inhomogeneity, count: 1, radius: 1.0, delta_n: {normal: [0.001, 0.0002]}, profile: uniform}
object: {ior: {normal: [1.5168, 0.0005]}, r1: {uniform: [48, 52]}}
ground_truth: {min_fraction: 0.5}
splits: {train: 0.8, val: 0.1, test: 0.1}
outputs: {ltm: true, previews: false}
max_attempts: 50
)"),
                                               "spec.yaml");
    EXPECT_EQ(s.samples, 12);
    EXPECT_EQ(s.seed, 7u);
    EXPECT_EQ(s.defect_free_fraction, 0.25);
    ASSERT_EQ(s.defects.size(), 5u);
    EXPECT_EQ(s.defects[0].count.kind, CountDistribution::Kind::Poisson);
    EXPECT_EQ(s.defects[1].semi_axes->at(1).kind, Distribution::Kind::Uniform);
    EXPECT_TRUE(s.defects[1].surface_breaking);
    EXPECT_EQ(s.defects[2].shape.options, std::vector<std::string>{"arc"});
    EXPECT_EQ(s.defects[2].scratch_profile.options.size(), 2u);
    EXPECT_EQ(s.defects[3].count.a, 1);  // the default count
    EXPECT_EQ(s.defects[4].index_profile.options, std::vector<std::string>{"uniform"});
    EXPECT_TRUE(s.object.ior && s.object.r1 && !s.object.r2);
    EXPECT_EQ(s.mask_fraction, 0.5);
    EXPECT_EQ(s.splits.size(), 3u);
    EXPECT_TRUE(s.keep_ltm);
    EXPECT_EQ(s.max_attempts, 50);
}

TEST(DatasetSpec, TheCanonicalFormIgnoresSpellingAndTheSampleCount) {
    const DatasetSpec a = parse_dataset_spec(spec_text("samples: 5\nseed: 2\ndefects: [{type: bubble, radius: 0.1}]\n"), "a");
    const DatasetSpec b = parse_dataset_spec(
        spec_text("seed: 2   # the same, written otherwise\nsamples: 900\ndefects:\n  - type: bubble\n    radius: 0.10\n"), "b");
    const DatasetSpec c = parse_dataset_spec(spec_text("samples: 5\nseed: 3\ndefects: [{type: bubble, radius: 0.1}]\n"), "c");
    EXPECT_EQ(a.canonical, b.canonical);
    EXPECT_NE(a.canonical, c.canonical);
}

TEST(DatasetSpec, BadInputIsLocated) {
    const std::string head = spec_text("samples: 4\n");
    // Line numbers: the scene takes lines 1-4, samples line 5.
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"defects: [{type: bubble, radius: {gauss: [0.1, 0.2]}}]\n",
         "spec.yaml:6:35: defects[0].radius.gauss: unknown distribution 'gauss'; the distributions are: uniform, "
         "log_uniform, normal"},
        {"defects: [{type: bubble, radius: {unifrom: [0.1, 0.2]}}]\n",
         "spec.yaml:6:35: defects[0].radius.unifrom: unknown distribution 'unifrom' (did you mean 'uniform'?)"},
        {"defects: [{type: bubble, radius: {uniform: [0.3, 0.2]}}]\n",
         "spec.yaml:6:44: defects[0].radius.uniform: the range [0.3, 0.2] is empty: its end must not be below its start"},
        {"defects: [{type: bubble, radius: {uniform: [-0.1, 0.2]}}]\n",
         "spec.yaml:6:44: defects[0].radius.uniform: the range [-0.1, 0.2] holds values <= 0; this parameter must be "
         "positive"},
        {"defects: [{type: bubble, count: 65}]\n",
         "spec.yaml:6:33: defects[0].count: expected a count from 0 to 64 (at most 64), got '65'"},
        {"defects: [{type: bubble, count: {poisson: 20}}]\n",
         "spec.yaml:6:43: defects[0].count.poisson: the mean must be in (0, 16] (the cap on a Poisson count), got 20"},
        {"defects: [{type: bubble, count: {uniform_int: [0, 100]}}]\n",
         "spec.yaml:6:51: defects[0].count.uniform_int[1]: expected a count from 0 to 64 (at most 64), got '100'"},
        {"defects: [{type: bubbel}]\n",
         "spec.yaml:6:18: defects[0].type: expected bubble, scratch, particle or inhomogeneity, got 'bubbel' (did you "
         "mean 'bubble'?)"},
        {"defects: [{type: scratch, radius: 0.1}]\n",
         "spec.yaml:6:27: defects[0].radius: unknown key 'radius' for a scratch kind (did you mean 'arc_radius'?)"},
        {"defect_free_fraction: 1.5\n", "spec.yaml:6:23: defect_free_fraction: must be in [0, 1], got 1.5"},
        {"splits: {train: 0.8, test: 0.1}\n", "spec.yaml:6:9: splits: the shares add up to 0.9, not 1"},
        {"sample: 3\n", "spec.yaml:6:1: sample: unknown key 'sample' (did you mean 'samples'?)"},
    };
    for (const auto& [tail, expected] : cases) EXPECT_EQ(error_of(head + tail), expected) << tail;
    // The base scene's own errors, at their lines in the spec (inline) ...
    EXPECT_EQ(error_of("scene:\n  object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: -6.0, diameter: 25.0, ior: "
                       "1.5}\nsamples: 2\ndefect_free_fraction: 1\n"),
              error_of("scene:\n  object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: -6.0, diameter: 25.0, ior: "
                       "1.5}\nsamples: 2\ndefect_free_fraction: 1\n"));
    EXPECT_NE(error_of("scene:\n  object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: -6.0, diameter: 25.0, ior: "
                       "1.5}\nsamples: 2\ndefect_free_fraction: 1\n")
                  .find("spec.yaml:2:"),
              std::string::npos);
    // ... or in its own file.
    const std::string missing = error_of("scene: no-such-scene.yaml\nsamples: 2\ndefect_free_fraction: 1\n");
    EXPECT_NE(missing.find("no-such-scene.yaml: cannot read scene file"), std::string::npos) << missing;
}

// ---- samples ----

TEST(Sampler, ASampleDependsOnTheSpecAndItsIndexOnly) {
    const DatasetSpec s = parse_dataset_spec(spec_text(R"(samples: 40
seed: 11
defect_free_fraction: 0.2
defects:
  - {type: bubble, count: {poisson: 2}, radius: {log_uniform: [0.05, 0.5]}}
  - {type: bubble, count: {uniform_int: [0, 1]}, surface_breaking: true, radius: 0.2}
  - {type: particle, count: {uniform_int: [0, 1]}, semi_axes: [0.3, 0.2, {uniform: [0.05, 0.1]}]}
  - {type: scratch, count: {uniform_int: [0, 2]}, shape: {choice: [straight, arc]}}
  - {type: inhomogeneity, count: {uniform_int: [0, 1]}, profile: {choice: [smooth, uniform]}}
object: {ior: {normal: [1.5168, 0.001]}}
)"),
                                             "spec.yaml");
    std::map<std::uint64_t, long> seeds;
    for (long i = 0; i < s.samples; ++i) {
        const SampleDraw a = draw_sample(s, i), b = draw_sample(s, i);
        EXPECT_EQ(a.scene_yaml, b.scene_yaml);
        EXPECT_EQ(a.seed, b.seed);
        seeds[a.seed] = i;
        // What scene.yaml says is what is rendered: it loads back to the same scene.
        const Scene back = parse_scene(a.scene_yaml, a.scene.source);
        EXPECT_EQ(scene_to_json(back), scene_to_json(a.scene));
        EXPECT_EQ(a.defect_free, a.scene.defects.empty());
        EXPECT_LE(a.scene.defects.size(), static_cast<size_t>(kMaxDefectsPerSample));
        EXPECT_EQ(a.kinds.size(), a.scene.defects.size());
        // What the sample says each defect drew is what its scene holds, under the keys that
        // sampled_keys lists for its entry (the card's list).
        ASSERT_EQ(a.sampled.size(), a.scene.defects.size());
        for (size_t j = 0; j < a.scene.defects.size(); ++j) {
            const Defect& d = a.scene.defects[j];
            const io::Json& got = a.sampled[j];
            std::vector<std::string> listed, have;
            for (const SampledKey& k : sampled_keys(s.defects[static_cast<size_t>(a.kinds[j])])) {
                const std::string base = k.key.substr(0, k.key.find('['));
                if ((listed.empty() || listed.back() != base) && !(base == "arc_radius" && !d.arc)) listed.push_back(base);
            }
            for (const auto& [key, value] : got.items()) have.push_back(key);
            EXPECT_EQ(have, listed);
            if (got.contains("radius")) {
                EXPECT_EQ(got["radius"].get<double>(), d.semi_axes.x);
            }
            if (got.contains("semi_axes")) {
                EXPECT_EQ(got["semi_axes"][2].get<double>(), d.semi_axes.z);
            }
            if (got.contains("width")) {
                EXPECT_EQ(got["width"].get<double>(), d.width);
            }
            if (got.contains("delta_n")) {
                EXPECT_EQ(got["delta_n"].get<double>(), d.delta_n);
            }
        }
        // Every placement rule holds (the loader checked them), and enclosed defects keep apart.
        const Lens lens(a.scene.object.lens);
        for (size_t j = 0; j < a.scene.defects.size(); ++j) {
            EXPECT_TRUE(defect_problems(lens, a.scene.defects[j], a.scene.object.index_field).empty());
            for (size_t k = 0; k < j; ++k) {
                const Defect &dj = a.scene.defects[j], &dk = a.scene.defects[k];
                if (!dj.is_ellipsoid() || !dk.is_ellipsoid()) continue;
                EXPECT_GT(distance(dj.center, dk.center), dj.max_semi_axis() + dk.max_semi_axis());
            }
        }
    }
    EXPECT_EQ(seeds.size(), static_cast<size_t>(s.samples));  // no two samples share a seed
    // Another spec seed changes the samples.
    DatasetSpec t = s;
    t.seed = 12;
    EXPECT_NE(draw_sample(t, 3).scene_yaml, draw_sample(s, 3).scene_yaml);
}

TEST(Sampler, TheDefectFreeShareAndTheSplitsFollowTheSpec) {
    const DatasetSpec s = parse_dataset_spec(
        spec_text("samples: 4000\nseed: 5\ndefect_free_fraction: 0.3\ndefects: [{type: bubble, radius: 0.1}]\n"
                  "splits: {train: 0.7, val: 0.2, test: 0.1}\n"),
        "spec.yaml");
    const long n = 4000;
    long free = 0;
    std::map<std::string, long> split;
    for (long i = 0; i < n; ++i) {
        const SampleDraw a = draw_sample(s, i);
        free += a.defect_free;
        ++split[a.split];
    }
    EXPECT_LT(std::fabs(z_of(static_cast<double>(free) / n, 0.3, 0.3 * 0.7, n)), kZ);
    EXPECT_LT(std::fabs(z_of(static_cast<double>(split["val"]) / n, 0.2, 0.2 * 0.8, n)), kZ);
    EXPECT_LT(std::fabs(z_of(static_cast<double>(split["test"]) / n, 0.1, 0.1 * 0.9, n)), kZ);
}

TEST(Sampler, ASizeThatFitsNowhereIsAnErrorAtItsKey) {
    // A 5 mm bubble in a 3 mm window: no position holds it.
    const DatasetSpec s = parse_dataset_spec(R"(scene:
  object: {type: window, thickness: 3.0, diameter: 25.0, ior: 1.5}
samples: 3
defects:
  - {type: bubble, radius: 5.0}
max_attempts: 100
)",
                                             "spec.yaml");
    const InputError e = draw_error(s, 0);
    EXPECT_EQ(e.line, 5);
    EXPECT_EQ(e.column, 28);
    EXPECT_EQ(e.key_path, "defects[0].radius");
    EXPECT_NE(std::string(e.what()).find("a bubble with radius 5 (sample 0) fits nowhere in the object: none of 100 "
                                         "positions holds it"),
              std::string::npos)
        << e.what();
}

TEST(Sampler, APitBelowItsFaceIsAnErrorAtItsCentreDepth) {
    // A pit of radius 0.2 centred 1 mm below its face never reaches the face: its center_depth,
    // not its radius, is what no position can mend.
    const DatasetSpec s = parse_dataset_spec(R"(scene:
  object: {type: window, thickness: 3.0, diameter: 25.0, ior: 1.5}
samples: 3
defects:
  - {type: bubble, radius: 0.2, surface_breaking: true, center_depth: 1.0}
max_attempts: 20
)",
                                             "spec.yaml");
    const InputError e = draw_error(s, 0);
    EXPECT_EQ(e.line, 5);
    EXPECT_EQ(e.key_path, "defects[0].center_depth");
    EXPECT_NE(std::string(e.what()).find("declared surface-breaking but lies entirely inside the glass"), std::string::npos)
        << e.what();
}

// The issue's scenario: a 1 mm window, 3 bubbles per sample, radius {log_uniform: [0.1, 0.4]}. A
// bubble of radius r fits where its centre is more than r from both faces, 1 - 2r of the
// thickness, so redrawing the size with the position skews sizes toward small ones (median 0.176
// instead of the requested sqrt(0.1 * 0.4) = 0.2; p = 3e-8 over 600 radii). Sizes drawn apart from
// the positions are the requested law's draws, bit for bit.
const char* kThinWindowSpec = R"(scene:
  object: {type: window, thickness: 1.0, diameter: 25.0, ior: 1.5}
samples: 1000
seed: 3
defects:
  - {type: bubble, count: 3, radius: {log_uniform: [0.1, 0.4]}}
)";

TEST(Sampler, SizesFollowTheSpecWhereverTheyFit) {
    const DatasetSpec s = parse_dataset_spec(kThinWindowSpec, "spec.yaml");
    std::vector<double> radii;
    for (long i = 0; i < s.samples; ++i)
        for (const Defect& d : draw_sample(s, i).scene.defects) radii.push_back(d.semi_axes.x);
    ASSERT_EQ(radii.size(), 3000u);
    const Distribution& law = *s.defects[0].radius;
    const double D = ks_statistic(radii, [&](double x) { return law.cdf(x); });
    // Independent draws of the requested law give p uniform on [0, 1]: p below alpha / checks is a
    // false alarm of this seeded test with that probability. Sizes redrawn with their positions
    // give D = 0.13 here, p = 6e-44.
    EXPECT_GT(ks_pvalue(static_cast<long>(radii.size()), D), tol::kFamilyAlpha / kChecks) << "D = " << D;
}

TEST(Sampler, SizesAreTheDrawsOfTheirLawsBitForBitAndCrowdedSamplesArePlacedAgain) {
    // 1. The thin window. 2. Two bubbles of radius 0.40-0.45 in a window 1 mm thick and 2 mm
    // across: each fits only within 0.1-0.2 mm of the mid-plane and 0.55-0.6 mm of the axis, and
    // the two only apart, so a first bubble placed near the axis leaves no room for the second and
    // the sample's positions are drawn again, its sizes kept.
    const std::string crowded = R"(scene:
  object: {type: window, thickness: 1.0, diameter: 2.0, ior: 1.5}
samples: 60
defects:
  - {type: bubble, count: 2, radius: {uniform: [0.40, 0.45]}}
)";
    int again = 0;
    for (const std::string& text : {std::string(kThinWindowSpec), crowded}) {
        const DatasetSpec s = parse_dataset_spec(text, "spec.yaml");
        const Distribution& law = *s.defects[0].radius;
        for (long i = 0; i < std::min(s.samples, 200L); ++i) {
            const SampleDraw a = draw_sample(s, i);
            Rng unconstrained(mix_seed(s.seed, static_cast<std::uint64_t>(i)), kParameterStream);
            ASSERT_EQ(a.scene.defects.size(), static_cast<size_t>(s.defects[0].count.a));
            for (const Defect& d : a.scene.defects) EXPECT_EQ(d.semi_axes.x, law.draw(unconstrained)) << "sample " << i;
            again += a.placement_rounds > 1;
        }
    }
    EXPECT_GT(again, 0);
}

TEST(Sampler, ANormalSizeIsTruncatedToItsRange) {
    // radius {normal: [0.05, 0.1]}: 31 % of the normal's draws are <= 0 and drawn again; the radii
    // follow the normal truncated to (0, inf), the law Distribution::cdf gives (KS at the file's
    // level, as above).
    const DatasetSpec s = parse_dataset_spec(
        spec_text("samples: 1000\ndefects: [{type: particle, count: 3, radius: {normal: [0.05, 0.1]}}]\n"), "spec.yaml");
    std::vector<double> radii;
    for (long i = 0; i < s.samples; ++i)
        for (const Defect& d : draw_sample(s, i).scene.defects) {
            ASSERT_GT(d.semi_axes.x, 0.0);
            radii.push_back(d.semi_axes.x);
        }
    const Distribution& law = *s.defects[0].radius;
    const double D = ks_statistic(radii, [&](double x) { return law.cdf(x); });
    EXPECT_GT(ks_pvalue(static_cast<long>(radii.size()), D), tol::kFamilyAlpha / kChecks) << "D = " << D;
}

TEST(Sampler, DefectsThatCannotFitTogetherAreAnErrorNamingTheSampleAndTheirSizes) {
    // Three bubbles of radius 0.45 in a window 1 mm thick and 2 mm across: each fits alone (centre
    // within 0.05 mm of the mid-plane, 0.55 mm of the axis), and three would need centres 0.9 mm
    // apart within 0.55 mm of the axis: an equilateral triangle of circumradius 0.52, a room no
    // random placement finds.
    const DatasetSpec s = parse_dataset_spec(R"(scene:
  object: {type: window, thickness: 1.0, diameter: 2.0, ior: 1.5}
samples: 1
defects:
  - {type: bubble, count: 3, radius: 0.45}
max_attempts: 200
)",
                                             "spec.yaml");
    const InputError e = draw_error(s, 0);
    EXPECT_EQ(e.line, 5);
    EXPECT_EQ(e.key_path, "defects[0]");
    const std::string m = e.what();
    EXPECT_NE(m.find("sample 0: its 3 defects do not fit together: 100 rounds of placing all of them, 200 positions "
                     "per defect, found no room for the bubble with radius 0.45"),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("The sizes, kept in every round: bubble (radius 0.45); bubble (radius 0.45); bubble (radius 0.45)"),
              std::string::npos)
        << m;
}

TEST(Sampler, ASizeRangeReachingBeyondTheObjectIsAnErrorAtItsKey) {
    // Radii up to 0.6 in a 1 mm window: a radius >= 0.5 fits nowhere (a bubble must stay clear of
    // both faces). With sizes redrawn until they fit, every sample would quietly draw below 0.5.
    const DatasetSpec s = parse_dataset_spec(R"(scene:
  object: {type: window, thickness: 1.0, diameter: 25.0, ior: 1.5}
samples: 100
defects:
  - type: bubble
    radius: {uniform: [0.3, 0.6]}
)",
                                             "spec.yaml");
    bool thrown = false;
    for (long i = 0; i < s.samples && !thrown; ++i) {
        try {
            draw_sample(s, i);
        } catch (const InputError& e) {
            thrown = true;
            EXPECT_EQ(e.file, "spec.yaml");
            EXPECT_EQ(e.line, 6);
            EXPECT_EQ(e.column, 13);
            EXPECT_EQ(e.key_path, "defects[0].radius");
            const std::string m = e.what();
            const auto at = m.find("a bubble with radius ");
            ASSERT_NE(at, std::string::npos) << m;
            // A radius r leaves 1 - 2r of the thickness for the centre: below 1/1000 of it (what
            // 1000 positions would likely miss) only for r > 0.4995.
            EXPECT_GT(std::stod(m.substr(at + 21)), 0.4995) << m;
            EXPECT_NE(m.find(fmt::format("(sample {}) fits nowhere in the object", i)), std::string::npos) << m;
        }
    }
    EXPECT_TRUE(thrown);
}

// ---- the dataset card ----

TEST(DatasetCard, ShowsEverySampledParametersRequestedAndRealisedLawWithItsTest) {
    const DatasetSpec spec = parse_dataset_spec(spec_text(R"(samples: 3
defect_free_fraction: 0.25
defects:
  - {type: bubble, count: {uniform_int: [1, 2]}, radius: {uniform: [0.1, 0.5]}}
  - {type: scratch, count: 1, width: 0.05, shape: straight, profile: {choice: [V, U]}}
)"),
                                                "spec.yaml");
    // Three samples (labels.json as the dataset writes them, cut to what the card reads): radii
    // 0.2, 0.3, 0.45; scratch profiles V, V, U and one more V; widths all 0.05; one defect-free.
    const auto defect = [](int entry, const char* kind, io::Json sampled) {
        return io::Json{{"kind", kind}, {"spec_entry", entry}, {"pixel_area", 1},
                        {"parameters", {{"size", 0.1}}}, {"sampled", std::move(sampled)}};
    };
    const auto scratch = [&](const char* profile) {
        return defect(1, "scratch", {{"surface", "front"}, {"width", 0.05}, {"depth", 0.02}, {"profile", profile},
                                     {"shape", "straight"}, {"length", 2.0}});
    };
    std::vector<io::Json> labels = {
        {{"split", "train"}, {"defect_free", false},
         {"defects", {defect(0, "bubble", {{"radius", 0.2}}), defect(0, "bubble", {{"radius", 0.3}}), scratch("V")}}},
        {{"split", "train"}, {"defect_free", false}, {"defects", {defect(0, "bubble", {{"radius", 0.45}}), scratch("V")}}},
        {{"split", "train"}, {"defect_free", false}, {"defects", {scratch("U"), scratch("V")}}},
        {{"split", "train"}, {"defect_free", true}, {"defects", io::Json::array()}},
    };
    const io::Json identity = {{"seed", 1}, {"requested", requested_parameters(spec)}};
    const auto dir = std::filesystem::temp_directory_path() / fmt::format("ltm-card-{}", ::getpid());
    write_dataset_card(dir.string(), identity, "samples: 3\n", labels, 4, {}, {});
    std::ifstream in(dir / "README.md");
    const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    std::filesystem::remove_all(dir);
    // Radii against U(0.1, 0.5): F = 0.25, 0.5, 0.875, so D = max(0.25 - 0, 1/3 - 0.25, 0.5 - 1/3,
    // 2/3 - 0.5, 0.875 - 2/3, 1 - 0.875) = 0.25; n D = 0.75, where P(D_3 < D) = 3!/3^3 (2 n D - 1)^3
    // = 1/36 (Ruben-Gambino): p = 0.97.
    EXPECT_NE(md.find("| defects[0] bubble radius | {uniform: [0.1, 0.5]} | 3 | 0.2 | 0.3 | 0.45 | 0.3167 | D = 0.2500 | 0.97 |"),
              std::string::npos)
        << md;
    // A constant: every value equal to it.
    EXPECT_NE(md.find("| defects[1] scratch width | 0.05 | 4 | 0.05 | 0.05 | 0.05 | 0.05 | constant | all equal |"),
              std::string::npos)
        << md;
    // Profiles V 3, U 1 against 2 each: chi2 = (1 + 1) / 2 = 1 on 1 dof, p = erfc(sqrt(1/2)) = 0.32.
    EXPECT_NE(md.find("| defects[1] scratch profile | {choice: [V, U]} | 4 | V 3, U 1 | chi2 = 1 (1 dof) | 0.32 |"),
              std::string::npos)
        << md;
    // Counts per sample that is not defect-free: bubbles 2, 1, 0.
    EXPECT_NE(md.find("| defects[0] bubble count | {uniform_int: [1, 2]} | 3 | 0 | 1 | 2 | 1 |"), std::string::npos) << md;
    EXPECT_NE(md.find("- defect-free samples: 1 (requested share 0.25: 1.0 expected)"), std::string::npos) << md;
}

TEST(Sampler, PitsThatWouldLeaveNoGlassMakeTheSpecInfeasible) {
    // A pit of radius 200 centred on the front face of a 25 mm window holds all of it (every point
    // of the window is within hypot(25, 3) = 25.2 mm of any point of that face): each draw is
    // refused as the loader refuses it, and the spec is an error before anything is rendered.
    const DatasetSpec s = parse_dataset_spec(R"(scene:
  object: {type: window, thickness: 3.0, diameter: 25.0, ior: 1.5}
samples: 3
defects:
  - {type: bubble, radius: 200.0, surface_breaking: true, surface: front}
max_attempts: 100
)",
                                             "spec.yaml");
    const InputError e = draw_error(s, 0);
    EXPECT_EQ(e.line, 5);
    EXPECT_EQ(e.key_path, "defects[0].radius");
    EXPECT_NE(std::string(e.what()).find("(radius 200 mm) holds the whole object"), std::string::npos) << e.what();
}

// ---- COCO RLE ----

TEST(CocoRle, CountsAndStringsFollowMaskApi) {
    // Hand-encoded (maskApi.c rleToString): counts [0, 100, 50, 20] -> "0" (0), "T3" (100 = 4 + 3 * 32:
    // 4 | 0x20 -> 'T', 3 -> '3'), "b1" (50 = 18 + 1 * 32, 18 has bit 0x10 so 1 != -1 continues: 50 -> 'b',
    // then '1'), and the fourth as 20 - 100 = -80 = 16 + (-3) * 32: 16 | 0x20 -> '`', then -3 & 31 = 29 -> 'M'.
    EXPECT_EQ(coco_rle_string({0, 100, 50, 20}), "0T3b1`M");
    EXPECT_EQ(coco_rle_decode("0T3b1`M"), (std::vector<std::uint32_t>{0, 100, 50, 20}));
    // Column-major runs starting with zeros: a 3 x 2 mask (width 3) with value 1 at (x=1, y=0)
    // and (x=1, y=1) and (x=2, y=1): columns read top to bottom are 0 0 | 1 1 | 0 1.
    const std::vector<std::uint16_t> m{0, 1, 0, 0, 1, 1};
    EXPECT_EQ(coco_rle_counts(m, 3, 2, 1), (std::vector<std::uint32_t>{2, 2, 1, 1}));
    EXPECT_EQ(coco_rle_counts(m, 3, 2, 2), (std::vector<std::uint32_t>{6}));
    // Random masks round-trip through the string form.
    std::mt19937_64 g(1);
    for (int t = 0; t < 200; ++t) {
        std::vector<std::uint16_t> r(37 * 23);
        for (auto& v : r) v = static_cast<std::uint16_t>(g() % 3);
        const auto c = coco_rle_counts(r, 37, 23, 1);
        EXPECT_EQ(coco_rle_decode(coco_rle_string(c)), c);
        long total = 0;
        for (auto x : c) total += x;
        EXPECT_EQ(total, 37 * 23);
    }
}

TEST(DatasetSpec, EveryShippedSpecLoadsAndCanBeMet) {
    int specs = 0;
    for (const auto& e : std::filesystem::directory_iterator(ltm::test::source_dir() + "/scenes/datasets")) {
        if (e.path().extension() != ".yaml") continue;
        ++specs;
        const DatasetSpec s = load_dataset_spec(e.path().string());
        for (long i = 0; i < std::min(s.samples, 200L); ++i) EXPECT_NO_THROW(draw_sample(s, i)) << e.path() << " " << i;
    }
    EXPECT_GE(specs, 2);
}
