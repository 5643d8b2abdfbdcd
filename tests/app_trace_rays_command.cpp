// The `ltmsim trace-rays` command's contract (docs: docs/conventions.md, "Command line"):
// one JSON object per input ray, in input order, on standard output,
//   {"vertices": [[x,y,z], ...], "surfaces": ["front", ...], "direction": [dx,dy,dz],
//    "display_hit": [x, y] | null, "display_pixel": [p, q] | null},
// for the principal path (transmitted at every interface, reflected only under TIR); pixel
// indices as in "Pixel indices"; bad input exits with status 2, a FILE:LINE message and nothing
// on standard output.
//
// Expected paths come from closed forms (axis, window) or from the independent analytic
// reference solver (validation/AnalyticScene.h) with the tolerances of `ltmsim validate`
// (validation/ValidationTolerance.h). Numbers are printed in the shortest form that round-trips
// (scene/SceneJson.h, json_number) and read back with strtod, so printing adds no error.
#include <algorithm>
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "geometry/Surface.h"
#include "scene/SceneLoader.h"
#include "tests/TestSupport.h"
#include "tests/Tolerances.h"
#include "validation/AnalyticScene.h"
#include "validation/TorusReference.h"
#include "validation/ValidationTolerance.h"

namespace fs = std::filesystem;
using ltm::Vec3;

namespace {

// ---- a minimal strict JSON reader for the output lines (independent of io/Json.cpp and nlohmann) ----
struct J {
    enum Type { Null, Bool, Number, String, Array, Object } type = Null;
    double number = 0;
    bool boolean = false;
    std::string string;
    std::vector<J> array;
    std::map<std::string, J> object;
    std::vector<std::string> keys;  // in order
};

class Parser {
public:
    explicit Parser(const std::string& s) : s_(s) {}
    bool document(J& out) {
        if (!value(out)) return false;
        ws();
        return i_ == s_.size();
    }

private:
    void ws() {
        while (i_ < s_.size() && (s_[i_] == ' ' || s_[i_] == '\t' || s_[i_] == '\r' || s_[i_] == '\n')) ++i_;
    }
    bool lit(const char* w) {
        const std::string x(w);
        if (s_.compare(i_, x.size(), x) != 0) return false;
        i_ += x.size();
        return true;
    }
    bool str(std::string& out) {
        if (i_ >= s_.size() || s_[i_] != '"') return false;
        for (++i_; i_ < s_.size(); ++i_) {
            const char c = s_[i_];
            if (c == '"') {
                ++i_;
                return true;
            }
            if (c == '\\' || static_cast<unsigned char>(c) < 0x20) return false;  // not needed here
            out += c;
        }
        return false;
    }
    bool value(J& v) {
        ws();
        if (i_ >= s_.size()) return false;
        const char c = s_[i_];
        if (c == '{') {
            v.type = J::Object;
            ++i_;
            ws();
            if (i_ < s_.size() && s_[i_] == '}') return ++i_, true;
            while (true) {
                ws();
                std::string k;
                if (!str(k) || v.object.count(k)) return false;
                ws();
                if (i_ >= s_.size() || s_[i_++] != ':') return false;
                J x;
                if (!value(x)) return false;
                v.object[k] = x;
                v.keys.push_back(k);
                ws();
                if (i_ < s_.size() && s_[i_] == ',') { ++i_; continue; }
                if (i_ < s_.size() && s_[i_] == '}') return ++i_, true;
                return false;
            }
        }
        if (c == '[') {
            v.type = J::Array;
            ++i_;
            ws();
            if (i_ < s_.size() && s_[i_] == ']') return ++i_, true;
            while (true) {
                J x;
                if (!value(x)) return false;
                v.array.push_back(x);
                ws();
                if (i_ < s_.size() && s_[i_] == ',') { ++i_; continue; }
                if (i_ < s_.size() && s_[i_] == ']') return ++i_, true;
                return false;
            }
        }
        if (c == '"') {
            v.type = J::String;
            return str(v.string);
        }
        if (lit("null")) return v.type = J::Null, true;
        if (lit("true")) return v.type = J::Bool, v.boolean = true, true;
        if (lit("false")) return v.type = J::Bool, true;
        // JSON number grammar only (no inf, nan, hex, leading '+' or '.').
        const size_t start = i_;
        if (s_[i_] == '-') ++i_;
        auto digits = [&] {
            const size_t d = i_;
            while (i_ < s_.size() && std::isdigit(static_cast<unsigned char>(s_[i_]))) ++i_;
            return i_ > d;
        };
        if (i_ < s_.size() && s_[i_] == '0') ++i_;
        else if (!digits()) return false;
        if (i_ < s_.size() && s_[i_] == '.') { ++i_; if (!digits()) return false; }
        if (i_ < s_.size() && (s_[i_] == 'e' || s_[i_] == 'E')) {
            ++i_;
            if (i_ < s_.size() && (s_[i_] == '+' || s_[i_] == '-')) ++i_;
            if (!digits()) return false;
        }
        v.type = J::Number;
        v.number = std::strtod(s_.substr(start, i_ - start).c_str(), nullptr);
        return std::isfinite(v.number);
    }
    const std::string& s_;
    size_t i_ = 0;
};

// One output line, checked against the contract's shape.
struct TracedRay {
    std::vector<Vec3> vertices;
    std::vector<std::string> surfaces;
    Vec3 direction;
    bool has_hit = false, has_pixel = false;
    double x = 0, y = 0;
    int p = -1, q = -1;
};

Vec3 vec3_of(const J& a) {
    EXPECT_EQ(a.type, J::Array);
    EXPECT_EQ(a.array.size(), 3u);
    Vec3 v;
    for (size_t i = 0; i < 3 && i < a.array.size(); ++i) {
        EXPECT_EQ(a.array[i].type, J::Number);
        v[static_cast<int>(i)] = a.array[i].number;
    }
    return v;
}

TracedRay parse_line(const std::string& line) {
    TracedRay r;
    J v;
    EXPECT_TRUE(Parser(line).document(v)) << "not one JSON value: " << line;
    EXPECT_EQ(v.type, J::Object) << line;
    EXPECT_EQ(v.keys, (std::vector<std::string>{"vertices", "surfaces", "direction", "display_hit", "display_pixel"}))
        << line;
    if (v.type != J::Object || v.object.size() != 5) return r;
    for (const J& x : v.object["vertices"].array) r.vertices.push_back(vec3_of(x));
    EXPECT_EQ(v.object["surfaces"].type, J::Array) << line;
    for (const J& s : v.object["surfaces"].array) {
        EXPECT_EQ(s.type, J::String) << line;
        r.surfaces.push_back(s.string);
    }
    EXPECT_EQ(r.surfaces.size(), r.vertices.size()) << line;
    r.direction = vec3_of(v.object["direction"]);
    const J& hit = v.object["display_hit"];
    if (hit.type != J::Null) {
        EXPECT_EQ(hit.type, J::Array) << line;
        EXPECT_EQ(hit.array.size(), 2u) << line;
        if (hit.array.size() == 2) {
            r.has_hit = true;
            r.x = hit.array[0].number;
            r.y = hit.array[1].number;
        }
    }
    const J& pix = v.object["display_pixel"];
    if (pix.type != J::Null) {
        EXPECT_EQ(pix.type, J::Array) << line;
        EXPECT_EQ(pix.array.size(), 2u) << line;
        if (pix.array.size() == 2) {
            r.has_pixel = true;
            r.p = static_cast<int>(pix.array[0].number);
            r.q = static_cast<int>(pix.array[1].number);
            EXPECT_EQ(double(r.p), pix.array[0].number) << "pixel indices are integers: " << line;
            EXPECT_EQ(double(r.q), pix.array[1].number) << "pixel indices are integers: " << line;
        }
    }
    return r;
}

using ltm::test::Outcome;

// The display of every scene here: 500 x 500 pixels over 100 x 100 mm at z = 60 (the paper's).
const char* kSetup =
    "camera: {resolution: [100, 100], size: [25.0, 25.0], numerical_aperture: 0.01, samples_per_pixel: 64}\n"
    "display: {resolution: [500, 500], size: [100.0, 100.0], z: 60.0}\n"
    "seed: 1\n";
const std::string kLens =
    std::string("object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}\n") + kSetup;
const std::string kWindow = std::string("object: {type: window, thickness: 3.0, diameter: 25.0, ior: 1.5}\n") + kSetup;
const std::string kDefects =
    std::string("object: {type: lens, r1: 50.0, r2: -50.0, center_thickness: 6.0, diameter: 25.0, ior: 1.5168}\n"
                "defects:\n"
                "  - {type: particle, center: [5.0, 5.0, 0.0], radius: 0.5}\n"
                "  - {type: bubble, center: [0.0, 0.0, 0.0], radius: 1.0}\n") +
    kSetup;

class TraceRaysCommand : public ltm::test::TempDirTest {
protected:
    // `ltmsim trace-rays`, capturing stdout and stderr.
    Outcome trace(const fs::path& scene, const fs::path& rays, const std::string& extra = "") {
        return ltm::test::ltmsim("trace-rays '" + scene.string() + "' --rays '" + rays.string() + "' " + extra, dir);
    }
};

// A traced ray against the analytic reference path of the same ray, with validate's tolerances.
void expect_matches_reference(const TracedRay& got, const ltm::validation::AnalyticScene& ref, const Vec3& o,
                              const Vec3& d) {
    namespace v = ltm::validation;
    const v::Path want = ref.principal_path(o, normalize(d));
    const ltm::validation::RaySensitivity s = ref.sensitivity(o, normalize(d));
    ASSERT_TRUE(s.stable) << "choose a well-conditioned ray";
    const double tol_pos = v::position_tolerance(s.interfaces, ref.length_scale(), s.kappa);
    const double tol_dir = v::direction_tolerance(s.interfaces, s.kappa_dir);
    EXPECT_EQ(got.surfaces, want.surfaces);
    ASSERT_EQ(got.vertices.size(), want.vertices.size());
    for (size_t i = 0; i < want.vertices.size(); ++i)
        EXPECT_LE(length(got.vertices[i] - want.vertices[i]), tol_pos) << "vertex " << i;
    EXPECT_LE(length(got.direction - want.direction), tol_dir);
    EXPECT_EQ(got.has_hit, want.display_hit && want.on_display);
    if (got.has_hit) {
        EXPECT_LE(std::hypot(got.x - want.display_x, got.y - want.display_y), tol_pos);
        ASSERT_TRUE(got.has_pixel);
        EXPECT_EQ(got.p, want.display_p);
        EXPECT_EQ(got.q, want.display_q);
    }
}

}  // namespace

TEST_F(TraceRaysCommand, AxialTiltedMissingAndBackwardRays) {
    const fs::path scene = write("lens.yaml", kLens);
    const Vec3 tilted_o{1.0, 2.0, -10.0}, tilted_d{0.05, -0.02, 1.0};  // not unit on purpose
    const fs::path rays = write("rays.jsonl",
                                "{\"origin\": [0,0,-10], \"direction\": [0,0,1]}\n"
                                "{\"origin\": [1,2,-10], \"direction\": [0.05,-0.02,1]}\n"
                                "{\"origin\": [20,0,-10], \"direction\": [0,0,1]}\n"
                                "{\"origin\": [0,0,-10], \"direction\": [0,0,-1]}\n");
    for (const char* rep : {"", "--representation refined"}) {
        SCOPED_TRACE(std::string("representation: ") + (*rep ? rep : "auto"));
        const Outcome r = trace(scene, rays, rep);
        ASSERT_EQ(r.status, 0) << r.err;
        const auto lines = r.lines();
        ASSERT_EQ(lines.size(), 4u) << r.out;

        // 1. The axial ray of a defect-free double-convex lens: front and back vertices at
        //    z = -t/2 and +t/2, undeviated, landing on the display's centre (0, 0), the corner of
        //    four pixels: p = floor((H/2 - y) / (H/P)) = 250, q = floor((x + W/2) / (W/Q)) = 250.
        const TracedRay axial = parse_line(lines[0]);
        EXPECT_EQ(axial.surfaces, (std::vector<std::string>{"front", "back"}));
        ASSERT_EQ(axial.vertices.size(), 2u);
        // Magnitudes of the sphere intersections: |o - c| + |R| <= |-10 - 47| + 50 (front face
        // from the origin; the back face from z ~ -3 has |-3 + 47| + 50, smaller).
        const double tv = ltm::tol::single_intersection(57.0 + 50.0);
        EXPECT_LE(length(axial.vertices[0] - Vec3{0, 0, -3}), tv) << lines[0];
        EXPECT_LE(length(axial.vertices[1] - Vec3{0, 0, 3}), tv) << lines[0];
        // On the axis every normal is (0, 0, +-1) and Snell's law leaves (0, 0, 1) unchanged: the
        // direction carries at most the rounding of the two Snell steps (closed_form_path with
        // L = 1 for unit vectors, no magnification on the axis).
        EXPECT_LE(length(axial.direction - Vec3{0, 0, 1}), ltm::tol::closed_form_path(2, 1.0, 0.0)) << lines[0];
        ASSERT_TRUE(axial.has_hit) << lines[0];
        // The hit moves by the direction's error times the 57 mm to the display, plus its own rounding.
        EXPECT_LE(std::hypot(axial.x, axial.y), ltm::tol::closed_form_path(2, 1.0, 0.0) * 60.0 + tv) << lines[0];
        ASSERT_TRUE(axial.has_pixel);
        EXPECT_EQ(axial.p, 250);
        EXPECT_EQ(axial.q, 250);

        // 2. A tilted ray: the analytic reference path.
        const ltm::Scene s = ltm::parse_scene(kLens, "lens.yaml");
        const ltm::validation::AnalyticScene ref(s);
        {
            SCOPED_TRACE(lines[1]);
            const TracedRay tilted = parse_line(lines[1]);
            EXPECT_EQ(tilted.surfaces, (std::vector<std::string>{"front", "back"}));
            EXPECT_NEAR(length(tilted.direction), 1.0, 4 * ltm::tol::kEps);
            expect_matches_reference(tilted, ref, tilted_o, tilted_d);
        }

        // 3. A ray outside the lens (rho = 20 > 12.5): no vertices, straight to x = 20 on the
        //    display: column floor((20 + 50) / 0.2) = 350, row floor((50 - 0) / 0.2) = 250.
        const TracedRay miss = parse_line(lines[2]);
        EXPECT_TRUE(miss.vertices.empty()) << lines[2];
        EXPECT_TRUE(miss.surfaces.empty()) << lines[2];
        EXPECT_EQ(miss.direction, (Vec3{0, 0, 1}));
        ASSERT_TRUE(miss.has_hit) << lines[2];
        EXPECT_EQ(miss.x, 20.0);
        EXPECT_EQ(miss.y, 0.0);
        ASSERT_TRUE(miss.has_pixel);
        EXPECT_EQ(miss.p, 250);
        EXPECT_EQ(miss.q, 350);

        // 4. A ray going away from the display: no hit, null and null.
        const TracedRay back = parse_line(lines[3]);
        EXPECT_TRUE(back.vertices.empty()) << lines[3];
        EXPECT_EQ(back.direction, (Vec3{0, 0, -1}));
        EXPECT_FALSE(back.has_hit) << lines[3];
        EXPECT_FALSE(back.has_pixel) << lines[3];
        // Explicit nulls, not missing keys (whatever spacing the writer uses).
        std::string compact = lines[3];
        compact.erase(std::remove(compact.begin(), compact.end(), ' '), compact.end());
        EXPECT_NE(compact.find("\"display_hit\":null"), std::string::npos) << lines[3];
        EXPECT_NE(compact.find("\"display_pixel\":null"), std::string::npos) << lines[3];
    }
}

TEST_F(TraceRaysCommand, SnellThroughAWindow) {
    // A plate of thickness t = 3 and index n = 1.5 (faces at z = -1.5 and +1.5) and a ray from
    // (0, 0, -10) at theta = 30 degrees to the axis in the x-z plane. In air the ray rises by
    // tan(theta) per unit of z; in the glass, by Snell's law sin(theta_g) = sin(theta) / n, by
    // tan(theta_g). The front face is reached after 8.5 mm of z, the back face 3 mm later, the
    // display (z = 60) 58.5 mm after that, so
    //   front vertex  x1 = 8.5 tan(theta)
    //   back vertex   x2 = x1 + 3 tan(theta_g)
    //   display hit   x  = x2 + 58.5 tan(theta) = 67 tan(theta) + 3 tan(theta_g),
    // i.e. displaced from the undeviated 70 tan(theta) by t (tan(theta_g) - tan(theta)); the two
    // parallel faces undo each other's refraction, so the ray leaves parallel to its input.
    const fs::path scene = write("window.yaml", kWindow);
    const double theta = M_PI / 6, n = 1.5;
    const double sin_t = std::sin(theta), cos_t = std::cos(theta), tan_t = sin_t / cos_t;
    const double sin_g = sin_t / n, tan_g = sin_g / std::sqrt(1 - sin_g * sin_g);
    const Vec3 o{0, 0, -10}, d{sin_t, 0, cos_t};
    std::ostringstream line;
    line.precision(17);
    line << "{\"origin\": [0, 0, -10], \"direction\": [" << sin_t << ", 0, " << cos_t << "]}\n";
    const fs::path rays = write("rays.jsonl", line.str());
    const Outcome r = trace(scene, rays);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto lines = r.lines();
    ASSERT_EQ(lines.size(), 1u) << r.out;
    const TracedRay got = parse_line(lines[0]);
    SCOPED_TRACE(lines[0]);

    // Tolerances: tests/Tolerances.h closed_form_path, with the path's length scale and its
    // sensitivities from the reference solver (validation/ValidationTolerance.h).
    const ltm::Scene s = ltm::parse_scene(kWindow, "window.yaml");
    const ltm::validation::AnalyticScene ref(s);
    const ltm::validation::RaySensitivity sens = ref.sensitivity(o, d);
    ASSERT_TRUE(sens.stable);
    const double tol_pos = ltm::tol::closed_form_path(2, ref.length_scale(), sens.kappa);
    const double tol_dir = ltm::tol::closed_form_path(2, 1.0, sens.kappa_dir);

    EXPECT_EQ(got.surfaces, (std::vector<std::string>{"front", "back"}));
    ASSERT_EQ(got.vertices.size(), 2u);
    EXPECT_LE(length(got.vertices[0] - Vec3{8.5 * tan_t, 0, -1.5}), tol_pos);
    EXPECT_LE(length(got.vertices[1] - Vec3{8.5 * tan_t + 3 * tan_g, 0, 1.5}), tol_pos);
    EXPECT_LE(length(got.direction - d), tol_dir) << "the ray leaves parallel to its input";
    ASSERT_TRUE(got.has_hit);
    const double x = 67 * tan_t + 3 * tan_g;
    EXPECT_LE(std::hypot(got.x - x, got.y), tol_pos) << "lateral displacement " << got.x - 70 * tan_t << ", expected "
                                                     << 3 * (tan_g - tan_t);
    // x = 39.74 mm: column floor((x + 50) / 0.2) = 448, row 250 (far from pixel edges).
    ASSERT_TRUE(got.has_pixel);
    EXPECT_EQ(got.p, 250);
    EXPECT_EQ(got.q, static_cast<int>(std::floor((x + 50) / 0.2)));
    EXPECT_EQ(got.q, 448);
}

TEST_F(TraceRaysCommand, DefectsAreNamedByTheirIndex) {
    // defects[0] is a particle, defects[1] a bubble at the centre: the axial ray crosses the
    // bubble (radius 1: vertices z = -1 and +1), a ray at (5, 5) is absorbed by the particle.
    const fs::path scene = write("defects.yaml", kDefects);
    const fs::path rays = write("rays.jsonl",
                                "{\"origin\": [0,0,-10], \"direction\": [0,0,1]}\n"
                                "{\"origin\": [5,5,-10], \"direction\": [0,0,1]}\n"
                                "{\"origin\": [0.3,-0.2,-10], \"direction\": [0,0.01,1]}\n");
    const ltm::Scene s = ltm::parse_scene(kDefects, "defects.yaml");
    const ltm::validation::AnalyticScene ref(s);
    for (const char* rep : {"", "--representation refined"}) {
        SCOPED_TRACE(std::string("representation: ") + (*rep ? rep : "auto"));
        const Outcome r = trace(scene, rays, rep);
        ASSERT_EQ(r.status, 0) << r.err;
        const auto lines = r.lines();
        ASSERT_EQ(lines.size(), 3u) << r.out;
        const TracedRay axial = parse_line(lines[0]);
        EXPECT_EQ(axial.surfaces, (std::vector<std::string>{"front", "bubble 1", "bubble 1", "back"})) << lines[0];
        ASSERT_EQ(axial.vertices.size(), 4u);
        const double tv = ltm::tol::single_intersection(57.0 + 50.0);
        const double z[4] = {-3, -1, 1, 3};
        for (int i = 0; i < 4; ++i) EXPECT_LE(length(axial.vertices[static_cast<size_t>(i)] - Vec3{0, 0, z[i]}), tv);
        EXPECT_TRUE(axial.has_hit);
        EXPECT_EQ(axial.p, 250);
        EXPECT_EQ(axial.q, 250);

        const TracedRay absorbed = parse_line(lines[1]);
        EXPECT_EQ(absorbed.surfaces, (std::vector<std::string>{"front", "particle 0"})) << lines[1];
        EXPECT_FALSE(absorbed.has_hit) << lines[1];
        EXPECT_FALSE(absorbed.has_pixel) << lines[1];

        SCOPED_TRACE(lines[2]);
        expect_matches_reference(parse_line(lines[2]), ref, Vec3{0.3, -0.2, -10}, Vec3{0, 0.01, 1});
    }
}

// --threads is used: the rays are traced in parallel, and the lines still come in input order,
// byte for byte the same whatever the number of threads (a principal path draws no random
// numbers). 2000 rays over the aperture, so that both threads trace many of them; line i is
// checked to be ray i's by its first vertex's x and y, which the axis-parallel ray keeps.
TEST_F(TraceRaysCommand, ThreadsChangeNothingAndKeepTheInputOrder) {
    const fs::path scene = write("defects.yaml", kDefects);
    std::string rays_text;
    std::vector<std::pair<double, double>> xy;
    for (int i = 0; i < 2000; ++i) {
        const double x = -8.0 + 16.0 * ((i * 37) % 2000) / 2000.0, y = -8.0 + 16.0 * ((i * 91) % 2000) / 2000.0;
        xy.emplace_back(x, y);
        rays_text += "{\"origin\": [" + std::to_string(x) + ", " + std::to_string(y) + ", -10], \"direction\": [0, 0, 1]}\n";
    }
    const fs::path rays = write("rays.jsonl", rays_text);
    const Outcome one = trace(scene, rays, "--threads 1");
    const Outcome two = trace(scene, rays, "--threads 2");
    ASSERT_EQ(one.status, 0) << one.err;
    ASSERT_EQ(two.status, 0) << two.err;
    EXPECT_EQ(one.out, two.out);
    const auto lines = two.lines();
    ASSERT_EQ(lines.size(), xy.size());
    for (size_t i = 0; i < lines.size(); i += 97) {
        const TracedRay r = parse_line(lines[i]);
        ASSERT_FALSE(r.vertices.empty()) << lines[i];
        EXPECT_DOUBLE_EQ(r.vertices[0].x, std::stod(std::to_string(xy[i].first))) << "line " << i;
        EXPECT_DOUBLE_EQ(r.vertices[0].y, std::stod(std::to_string(xy[i].second))) << "line " << i;
    }
}

TEST_F(TraceRaysCommand, BlankLinesAreAllowed) {
    const fs::path scene = write("lens.yaml", kLens);
    const fs::path rays = write("rays.jsonl",
                                "\n{\"origin\": [0,0,-10], \"direction\": [0,0,1]}\n"
                                "   \t\n"
                                "{\"direction\": [0,0,-1], \"origin\": [0,0,-10]}\r\n"
                                "\n");
    const Outcome r = trace(scene, rays);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto lines = r.lines();
    ASSERT_EQ(lines.size(), 2u) << r.out;  // one output line per ray, in order
    EXPECT_TRUE(parse_line(lines[0]).has_hit);
    EXPECT_EQ(parse_line(lines[1]).direction, (Vec3{0, 0, -1}));
}

TEST_F(TraceRaysCommand, BadRaysExitTwoWithFileAndLineAndPrintNothing) {
    const fs::path scene = write("lens.yaml", kLens);
    const std::string good = "{\"origin\": [0,0,-10], \"direction\": [0,0,1]}\n";
    struct Case {
        const char* name;
        std::string line;   // line 2 of 3
        const char* says;   // part of the message after "FILE:2:"
    };
    const std::vector<Case> cases = {
        {"malformed JSON", "{\"origin\": [0,0,-10], \"direction\": [0,0,1]", "malformed JSON"},
        {"zero direction", "{\"origin\": [0,0,-10], \"direction\": [0,0,0]}", "direction"},
        {"non-finite number", "{\"origin\": [0,0,-10], \"direction\": [0,0,1e999]}", "finite"},
        {"negative overflow", "{\"origin\": [-1e999,0,-10], \"direction\": [0,0,1]}", "finite"},
        {"missing key", "{\"origin\": [0,0,-10]}", "direction"},
        {"unknown key", "{\"origin\": [0,0,-10], \"direction\": [0,0,1], \"colour\": 1}", "colour"},
        {"list of 2 numbers", "{\"origin\": [0,0], \"direction\": [0,0,1]}", "origin"},
        {"a string for a number", "{\"origin\": [0,\"0\",-10], \"direction\": [0,0,1]}", "origin"},
        {"NaN is not JSON", "{\"origin\": [0,0,-10], \"direction\": [0,0,NaN]}", "malformed JSON"},
        {"duplicate key", "{\"origin\": [0,0,-10], \"origin\": [0,0,-10], \"direction\": [0,0,1]}", "origin"},
        {"not an object", "[[0,0,-10], [0,0,1]]", "object"},
        {"trailing text", "{\"origin\": [0,0,-10], \"direction\": [0,0,1]} x", "malformed JSON"},
    };
    for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const fs::path rays = write("bad.jsonl", good + c.line + "\n" + good);
        const Outcome r = trace(scene, rays);
        EXPECT_EQ(r.status, 2) << r.err;
        EXPECT_EQ(r.out, "") << "nothing on standard output";
        const std::string where = rays.string() + ":2:";
        const size_t at = r.err.find(where);
        ASSERT_NE(at, std::string::npos) << r.err;
        EXPECT_NE(r.err.find(c.says, at), std::string::npos) << r.err;
    }
    // Lines are counted in the file, blank ones included.
    const fs::path rays = write("bad.jsonl", good + "\n" + "{\"origin\": [0,0,-10], \"direction\": [0,0,0]}\n");
    const Outcome r = trace(scene, rays);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err.find(rays.string() + ":3:"), std::string::npos) << r.err;
}

TEST_F(TraceRaysCommand, MissingRaysFileOrBadSceneExitTwo) {
    const fs::path scene = write("lens.yaml", kLens);
    const fs::path nope = dir / "nope.jsonl";
    Outcome r = trace(scene, nope);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err.find(nope.string()), std::string::npos) << r.err;

    const fs::path rays = write("rays.jsonl", "{\"origin\": [0,0,-10], \"direction\": [0,0,1]}\n");
    const fs::path bad = write("bad.yaml", "object: {type: lens, r1: 50, r2: -50, center_thickness: 6, diametre: 25, ior: 1.5}\n");
    r = trace(bad, rays);
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err.find(bad.string() + ":1:"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("object.diametre"), std::string::npos) << r.err;

    // The analytic representation is refused for a surface-breaking defect, with the reason.
    const std::string pit = ltm::test::source_dir() + "/scenes/examples/pit.yaml";
    r = trace(pit, rays, "--representation analytic");
    EXPECT_EQ(r.status, 2);
    EXPECT_EQ(r.out, "");
    EXPECT_NE(r.err.find(pit), std::string::npos) << r.err;
}

// The input is a direction: any finite, non-zero vector, whatever its length. A huge one must
// give the same path as its unit vector (and a unit "direction" out), a tiny one must not be
// rejected as the zero vector. Both are finite JSON numbers, so neither is bad input.
static void expect_same_as_unit(const Outcome& r) {
    EXPECT_EQ(r.status, 0) << r.err;
    const auto lines = r.lines();
    ASSERT_EQ(lines.size(), 2u) << r.out << r.err;
    const TracedRay unit = parse_line(lines[0]);
    ASSERT_EQ(unit.surfaces, (std::vector<std::string>{"front", "back"}));
    SCOPED_TRACE(lines[1]);
    const TracedRay scaled = parse_line(lines[1]);
    EXPECT_NEAR(length(scaled.direction), 1.0, 4 * ltm::tol::kEps) << "the final direction is a unit vector";
    EXPECT_EQ(scaled.surfaces, unit.surfaces);
    // The same ray up to the rounding of its normalised direction (a few ulps), magnified along
    // the path: validate's tolerance for this path covers it.
    const ltm::Scene s = ltm::parse_scene(kLens, "lens.yaml");
    const ltm::validation::AnalyticScene ref(s);
    expect_matches_reference(scaled, ref, Vec3{0, 0, -10}, Vec3{0.1, 0, 1});
}

TEST_F(TraceRaysCommand, AHugeDirectionIsADirection) {
    // |d| = 1e201 (squaring it overflows a double).
    const fs::path scene = write("lens.yaml", kLens);
    const fs::path rays = write("rays.jsonl",
                                "{\"origin\": [0,0,-10], \"direction\": [0.1,0,1]}\n"
                                "{\"origin\": [0,0,-10], \"direction\": [1e200,0,1e201]}\n");
    expect_same_as_unit(trace(scene, rays));
}

TEST_F(TraceRaysCommand, ATinyDirectionIsNotTheZeroVector) {
    // |d| = 1e-170 (squaring it underflows to 0).
    const fs::path scene = write("lens.yaml", kLens);
    const fs::path rays = write("rays.jsonl",
                                "{\"origin\": [0,0,-10], \"direction\": [0.1,0,1]}\n"
                                "{\"origin\": [0,0,-10], \"direction\": [1e-171,0,1e-170]}\n");
    expect_same_as_unit(trace(scene, rays));
}

TEST_F(TraceRaysCommand, AGrazingChordThroughAUGrooveIsFound) {
    // The reproduction: a window (thickness 6: front face z = -3) with a U scratch on the
    // front face along the arc of radius 5 about the axis, 30..150 degrees. U profile of width
    // w = 0.2 and depth d = 0.05: a circular bottom of radius rb = (w^2 / 4 + d^2) / (2 d) = 0.125
    // whose centre is rb - d = 0.075 outside the glass, so the groove's bottom is the torus of
    // centre (0, 0, -3.075), axis z, radii 5 and 0.125, lowest point (deepest in the glass)
    // z = -2.95. At x = 0 (90 degrees) the ray along +y at z = -2.950001 runs 1e-6 mm on the void
    // side of that point, inside the glass elsewhere: it meets the groove in a chord of
    // 2 sqrt(rb^2 - (rb - 1e-6)^2) ~ 1e-3 mm, at grazing incidence from the glass (total internal
    // reflection), and goes on to the rim. The same chord from the other side, and a ray 1e-6 mm
    // deeper in the glass, which passes under the groove and meets only the rim.
    const std::string scene_text =
        std::string("object: {type: window, thickness: 6.0, diameter: 30.0, ior: 1.5}\n"
                    "defects:\n"
                    "  - type: scratch\n"
                    "    surface: front\n"
                    "    arc: {center: [0.0, 0.0], radius: 5.0, start_angle: 30.0, end_angle: 150.0}\n"
                    "    width: 0.2\n"
                    "    depth: 0.05\n"
                    "    profile: U\n") +
        kSetup;
    const fs::path scene = write("groove.yaml", scene_text);
    const fs::path rays = write("rays.jsonl",
                                "{\"origin\": [0, 4.5, -2.950001], \"direction\": [0, 1, 0]}\n"
                                "{\"origin\": [0, 5.5, -2.950001], \"direction\": [0, -1, 0]}\n"
                                "{\"origin\": [0, 4.5, -2.949999], \"direction\": [0, 1, 0]}\n");
    const Outcome r = trace(scene, rays);
    ASSERT_EQ(r.status, 0) << r.err;
    const auto lines = r.lines();
    ASSERT_EQ(lines.size(), 3u) << r.out;

    // The expected first vertices from the exact torus reference (validation/TorusReference.h) on
    // the nominal torus; the tolerance (tests/Tolerances.h): the tracer's root error torus_root,
    // the built torus's offset from the nominal one torus_built_shift, and the rounding of
    // o + t d (one ulp of y).
    const ltm::Surface nominal = ltm::Surface::torus({0, 0, -3.075}, {0, 0, 1}, 5.0, 0.125);
    const double R = nominal.radius, rb = nominal.minor_radius;
    const double M = length(nominal.origin) + R + rb;
    for (int k = 0; k < 2; ++k) {
        SCOPED_TRACE(lines[static_cast<size_t>(k)]);
        const Vec3 o{0, k == 0 ? 4.5 : 5.5, -2.950001}, d{0, k == 0 ? 1.0 : -1.0, 0};
        const ltm::validation::TorusReference ref(nominal.origin, nominal.axis, R, rb, o, d);
        // The full torus: the chord at y ~ 5 and its mirror at y ~ -5 (where the scratch's arc
        // does not reach); the first root ahead is the chord's near end.
        ASSERT_EQ(ref.roots().size(), 4u);
        size_t i = 0;
        while (i + 1 < 4 && ref.roots()[i].t <= 0) ++i;
        ASSERT_LT(i + 1, 4u);
        const ltm::validation::TorusRoot& first = ref.roots()[i];
        EXPECT_LT(ref.roots()[i + 1].t - first.t, 1.01e-3) << "the chord";
        EXPECT_GT(ref.roots()[i + 1].t - first.t, 0.99e-3) << "the chord";
        const double tm = dot(nominal.origin - o, d);
        const Vec3 p = o + d * tm - nominal.origin;
        const double E = ltm::tol::torus_f_error(R, rb, dot(p, p), dot(p, nominal.axis), dot(d, nominal.axis), first.t - tm,
                                                 length(o) + std::fabs(tm) + length(nominal.origin));
        const double rho = std::fabs(o.y + first.t * d.y);
        const double cos_incidence = first.slope / (8 * R * rb * rho);
        const double tol = ltm::tol::torus_root(E, first.slope, first.curvature, first.t, first.t - tm) +
                           ltm::tol::torus_built_shift(M, cos_incidence) + 2 * (ltm::tol::kEps / 2) * rho;
        const TracedRay got = parse_line(lines[static_cast<size_t>(k)]);
        EXPECT_EQ(got.surfaces, (std::vector<std::string>{"scratch 0 bottom", "rim"}));
        ASSERT_FALSE(got.vertices.empty());
        EXPECT_EQ(got.vertices[0].x, 0.0);
        EXPECT_EQ(got.vertices[0].z, -2.950001);
        EXPECT_LE(std::fabs(got.vertices[0].y - (o.y + first.t * d.y)), tol)
            << "reference " << o.y + first.t * d.y << ", tolerance " << tol;
    }
    // 1e-6 mm deeper: under the groove (the exact f stays positive along the ray), only the rim.
    const TracedRay under = parse_line(lines[2]);
    EXPECT_EQ(under.surfaces, (std::vector<std::string>{"rim"})) << lines[2];
    const ltm::validation::TorusReference miss(nominal.origin, nominal.axis, R, rb, {0, 4.5, -2.949999}, {0, 1, 0});
    EXPECT_TRUE(miss.roots().empty()) << "the ray passes under the whole torus";
}
