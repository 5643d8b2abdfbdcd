#include "features/Features.h"

#include "io/Pages.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numeric>
#include <sstream>
#include <stdexcept>

namespace ltm {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kPi = 3.14159265358979323846;

// Channel positions in FeatureImages::channels (the order of feature_channel_names).
enum Channel : int {
    kBrightField,
    kDarkField,
    kScatterCount,
    kScatterWidth,
    kScatterRows,
    kScatterColumns,
    kScatterDiameter,
    kEllipseMajor,
    kEllipseMinor,
    kEllipseAngle,
    kRobustScatterCount,
    kRobustScatterDiameter,
    kMeanX,
    kMeanY,
    kDeflectionX,
    kDeflectionY,
    kDeflection,
    kChannelCount
};

// A display pixel as integer (row p, column q). Points are kept in increasing (p, q) order, which
// is increasing linear index l = p Q + q, i.e. the order of a CSR row: the monotone chain needs
// its points sorted lexicographically, and any coordinate order will do for a hull.
struct Pixel {
    std::int64_t p, q;
};

// Twice the signed area of (o, a, b). |dp| < P and |dq| < Q with P Q < 2^31 (int32 columns), so
// each product is below 2^31 and the result is exact.
std::int64_t cross(const Pixel& o, const Pixel& a, const Pixel& b) {
    return (a.p - o.p) * (b.q - o.q) - (a.q - o.q) * (b.p - o.p);
}

std::int64_t squared_distance(const Pixel& a, const Pixel& b) {
    const std::int64_t dp = a.p - b.p, dq = a.q - b.q;
    return dp * dp + dq * dq;
}

// The squared diameter of a set of distinct pixels sorted by (p, q): the farthest pair lies on the
// convex hull, so the hull (Andrew's monotone chain; collinear points dropped) is built in O(n)
// and its vertex pairs are compared exhaustively. Integer pixels in a P x Q box have
// O((P + Q)^(2/3)) hull vertices at most, a few hundred for a 500 x 500 display, so the quadratic
// pass over the hull costs little next to the O(n) chain; it is exact, as is everything here.
std::int64_t squared_diameter(const std::vector<Pixel>& pts, std::vector<Pixel>& hull) {
    const std::size_t n = pts.size();
    if (n < 2) return 0;
    if (n == 2) return squared_distance(pts[0], pts[1]);
    hull.resize(2 * n);
    std::size_t k = 0;
    for (std::size_t i = 0; i < n; ++i) {  // lower chain
        while (k >= 2 && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
        hull[k++] = pts[i];
    }
    for (std::size_t i = n - 1, lower = k + 1; i-- > 0;) {  // upper chain
        while (k >= lower && cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
        hull[k++] = pts[i];
    }
    const std::size_t h = k - 1;  // the last vertex repeats the first
    std::int64_t best = 0;
    for (std::size_t i = 0; i < h; ++i)
        for (std::size_t j = i + 1; j < h; ++j) best = std::max(best, squared_distance(hull[i], hull[j]));
    return best;
}

// Per-chunk scratch space, reused row after row.
struct Scratch {
    std::vector<std::int32_t> cols;   // contributing columns, increasing
    std::vector<double> vals;         // their values
    std::vector<std::uint32_t> order; // positions into cols/vals, by value descending
    std::vector<char> keep;           // robust selection flags
    std::vector<Pixel> pts, hull;
};

struct Setup {
    const CsrMatrix* T;
    std::int64_t Q;
    double width, height, Pd, Qd;
    double threshold, fraction;
    std::int64_t block_p0, block_p1, block_q0, block_q1;  // dark block [p0, p1) x [q0, q1)
    const std::vector<float>* reference;
    float* out[kChannelCount];
};

// The entries of row r above the threshold, into w.cols and w.vals (columns increasing).
void kept_entries(const Setup& s, std::int64_t r, Scratch& w) {
    const CsrMatrix& T = *s.T;
    w.cols.clear();
    w.vals.clear();
    for (auto i = static_cast<std::size_t>(T.indptr[static_cast<std::size_t>(r)]);
         i < static_cast<std::size_t>(T.indptr[static_cast<std::size_t>(r) + 1]); ++i) {
        const double v = static_cast<double>(T.data[i]);
        if (v > s.threshold) {
            w.cols.push_back(T.indices[i]);
            w.vals.push_back(v);
        }
    }
}

// The value-weighted mean display pixel of a row's kept entries (w.pts, w.vals; at least one),
// as offsets (mx, my) from the first one, o, and as a position (x, y) in mm on the display.
// Moments about the first pixel: the offsets are small exact integers, so a single pixel gives a
// mean offset of exactly 0 (and a covariance of exactly 0), and nothing cancels against the
// absolute position. (x, y) = (q, -p): y up.
struct Mean {
    Pixel o;
    double wsum, mx, my;
    double x, y;
};

Mean row_mean(const Setup& s, const Scratch& w) {
    Mean m;
    m.o = w.pts.front();
    double wsum = 0, sx = 0, sy = 0;
    for (std::size_t i = 0; i < w.pts.size(); ++i) {
        wsum += w.vals[i];
        sx += w.vals[i] * static_cast<double>(w.pts[i].q - m.o.q);
        sy += w.vals[i] * static_cast<double>(m.o.p - w.pts[i].p);
    }
    m.wsum = wsum;
    m.mx = sx / wsum;
    m.my = sy / wsum;
    const double mean_q = static_cast<double>(m.o.q) + m.mx;
    const double mean_p = static_cast<double>(m.o.p) - m.my;
    m.x = -0.5 * s.width + (mean_q + 0.5) * (s.width / s.Qd);
    m.y = 0.5 * s.height - (mean_p + 0.5) * (s.height / s.Pd);
    return m;
}

void row_features(const Setup& s, std::int64_t r, Scratch& w) {
    const CsrMatrix& T = *s.T;
    const auto b = static_cast<std::size_t>(T.indptr[static_cast<std::size_t>(r)]);
    const auto e = static_cast<std::size_t>(T.indptr[static_cast<std::size_t>(r) + 1]);
    const auto k = static_cast<std::size_t>(r);

    // BrightField and DarkField: T x with x = 1 and x = 0/1, accumulated in column order exactly as
    // CsrMatrix::multiply does (x[l] = 1 gives the same products; x[l] = 0 adds 0).
    double bright = 0.0, dark = 0.0;
    w.cols.clear();
    w.vals.clear();
    for (std::size_t i = b; i < e; ++i) {
        const std::int32_t l = T.indices[i];
        const double v = static_cast<double>(T.data[i]);
        bright += v;
        const std::int64_t p = l / s.Q, q = l % s.Q;
        const bool in_block = p >= s.block_p0 && p < s.block_p1 && q >= s.block_q0 && q < s.block_q1;
        dark += in_block ? 0.0 * v : 1.0 * v;
        if (v > s.threshold) {
            w.cols.push_back(l);
            w.vals.push_back(v);
        }
    }
    s.out[kBrightField][k] = static_cast<float>(bright);
    s.out[kDarkField][k] = static_cast<float>(dark);

    const std::size_t n = w.cols.size();
    double count = 0, width = 0, rows = 0, columns = 0, diameter = 0;
    double major = 0, minor = 0, angle = 0, robust_count = 0, robust_diameter = 0;
    double mean_x = kNaN, mean_y = kNaN;
    if (n > 0) {
        count = static_cast<double>(n);
        const std::int64_t first = w.cols.front(), last = w.cols.back();
        width = static_cast<double>(last - first);
        rows = static_cast<double>(last / s.Q - first / s.Q);  // columns increase, so rows do too
        std::int64_t qmin = first % s.Q, qmax = qmin;
        w.pts.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const std::int64_t p = w.cols[i] / s.Q, q = w.cols[i] % s.Q;
            w.pts[i] = {p, q};
            qmin = std::min(qmin, q);
            qmax = std::max(qmax, q);
        }
        columns = static_cast<double>(qmax - qmin);
        const std::int64_t d2 = squared_diameter(w.pts, w.hull);
        diameter = std::sqrt(static_cast<double>(d2));

        const Mean mean = row_mean(s, w);
        const Pixel o = mean.o;
        const double wsum = mean.wsum, mx = mean.mx, my = mean.my;
        double cxx = 0, cxy = 0, cyy = 0;
        for (std::size_t i = 0; i < n; ++i) {
            const double dx = static_cast<double>(w.pts[i].q - o.q) - mx;
            const double dy = static_cast<double>(o.p - w.pts[i].p) - my;
            cxx += w.vals[i] * dx * dx;
            cxy += w.vals[i] * dx * dy;
            cyy += w.vals[i] * dy * dy;
        }
        cxx /= wsum;
        cxy /= wsum;
        cyy /= wsum;
        // Eigenvalues of [[cxx, cxy], [cxy, cyy]]: m +- r; the major axis is at
        // 0.5 atan2(2 cxy, cxx - cyy), in [-90, 90] degrees; -90 (from atan2(-0, negative)) is the
        // same axis as 90, which is the one reported.
        const double m = 0.5 * (cxx + cyy), half = 0.5 * (cxx - cyy);
        const double rad = std::hypot(half, cxy);
        major = 2.0 * std::sqrt(m + rad);
        minor = 2.0 * std::sqrt(std::max(m - rad, 0.0));
        angle = (cxy == 0.0 && half == 0.0) ? 0.0 : 0.5 * std::atan2(2.0 * cxy, cxx - cyy) * (180.0 / kPi);
        if (angle <= -90.0) angle += 180.0;

        mean_x = mean.x;
        mean_y = mean.y;

        // Robust: the largest values first until the fraction of the energy is reached.
        w.order.resize(n);
        std::iota(w.order.begin(), w.order.end(), 0u);
        std::sort(w.order.begin(), w.order.end(), [&](std::uint32_t a, std::uint32_t c) {
            return w.vals[a] > w.vals[c] || (w.vals[a] == w.vals[c] && a < c);  // a < c: column order
        });
        double total = 0;
        for (std::uint32_t i : w.order) total += w.vals[i];
        const double target = s.fraction * total;  // <= total: the loop below stops within the row
        std::size_t taken = 0;
        double cum = 0;
        while (taken < n) {
            cum += w.vals[w.order[taken++]];
            if (cum >= target) break;
        }
        robust_count = static_cast<double>(taken);
        if (taken == n) {
            robust_diameter = diameter;
        } else {
            w.keep.assign(n, 0);
            for (std::size_t i = 0; i < taken; ++i) w.keep[w.order[i]] = 1;
            std::size_t j = 0;
            for (std::size_t i = 0; i < n; ++i)
                if (w.keep[i]) w.pts[j++] = w.pts[i];  // stays in column order
            w.pts.resize(j);
            robust_diameter = std::sqrt(static_cast<double>(squared_diameter(w.pts, w.hull)));
        }
    }
    s.out[kScatterCount][k] = static_cast<float>(count);
    s.out[kScatterWidth][k] = static_cast<float>(width);
    s.out[kScatterRows][k] = static_cast<float>(rows);
    s.out[kScatterColumns][k] = static_cast<float>(columns);
    s.out[kScatterDiameter][k] = static_cast<float>(diameter);
    s.out[kEllipseMajor][k] = static_cast<float>(major);
    s.out[kEllipseMinor][k] = static_cast<float>(minor);
    s.out[kEllipseAngle][k] = static_cast<float>(angle);
    s.out[kRobustScatterCount][k] = static_cast<float>(robust_count);
    s.out[kRobustScatterDiameter][k] = static_cast<float>(robust_diameter);
    s.out[kMeanX][k] = static_cast<float>(mean_x);
    s.out[kMeanY][k] = static_cast<float>(mean_y);
    if (s.reference) {
        // From the stored (float) means, so that a row equal to its reference row gives exactly 0.
        const double mx = static_cast<double>(s.out[kMeanX][k]), my = static_cast<double>(s.out[kMeanY][k]);
        const double rx = static_cast<double>((*s.reference)[2 * k]);
        const double ry = static_cast<double>((*s.reference)[2 * k + 1]);
        double dx = mx - rx, dy = my - ry, d = std::hypot(dx, dy);
        if (std::isnan(dx) || std::isnan(dy)) dx = dy = d = kNaN;  // hypot(NaN, inf) would be inf
        s.out[kDeflectionX][k] = static_cast<float>(dx);
        s.out[kDeflectionY][k] = static_cast<float>(dy);
        s.out[kDeflection][k] = static_cast<float>(d);
    }
}

void check_matrix(const CsrMatrix& T, const char* who) {
    const std::string problem = T.check();
    if (!problem.empty()) throw std::invalid_argument(std::string(who) + ": T is not a valid CSR matrix: " + problem);
}

}  // namespace

const std::vector<std::string>& feature_channel_names(bool with_reference) {
    static const std::vector<std::string> all = {
        "BrightField",     "DarkField",      "ScatterCount",       "ScatterWidth",          "ScatterRows",
        "ScatterColumns",  "ScatterDiameter", "EllipseMajor",      "EllipseMinor",          "EllipseAngle",
        "RobustScatterCount", "RobustScatterDiameter", "MeanX",    "MeanY",                 "DeflectionX",
        "DeflectionY",     "Deflection"};
    static const std::vector<std::string> without(all.begin(), all.begin() + kDeflectionX);
    return with_reference ? all : without;
}

std::string feature_unit(const std::string& channel) {
    static const std::vector<std::pair<std::string, std::string>> units = {
        {"BrightField", "fraction"},         {"DarkField", "fraction"},
        {"ScatterCount", "count"},           {"ScatterWidth", "index"},
        {"ScatterRows", "display pixels"},   {"ScatterColumns", "display pixels"},
        {"ScatterDiameter", "display pixels"}, {"EllipseMajor", "display pixels"},
        {"EllipseMinor", "display pixels"},  {"EllipseAngle", "degrees"},
        {"RobustScatterCount", "count"},     {"RobustScatterDiameter", "display pixels"},
        {"MeanX", "mm"},                     {"MeanY", "mm"},
        {"DeflectionX", "mm"},               {"DeflectionY", "mm"},
        {"Deflection", "mm"}};
    for (const auto& [name, unit] : units)
        if (name == channel) return unit;
    return "";
}

std::string feature_title(const std::string& channel) {
    const std::string unit = feature_unit(channel);
    return unit.empty() ? channel : channel + " (" + unit + ")";
}

const std::vector<float>& FeatureImages::channel(const std::string& name) const {
    for (const auto& c : channels)
        if (c.first == name) return c.second;
    std::ostringstream os;
    os << "feature channel '" << name << "' not found (channels:";
    for (const auto& c : channels) os << ' ' << c.first;
    os << ')';
    throw std::out_of_range(os.str());
}

FeatureImages compute_features(const CsrMatrix& T, int camera_columns, int camera_rows, const DisplayGrid& display,
                               const FeatureOptions& options, const std::vector<float>* reference_mean) {
    const char* who = "compute_features";
    auto fail = [&](const std::string& what) { throw std::invalid_argument(std::string(who) + ": " + what); };
    std::ostringstream os;
    if (camera_columns < 1 || camera_rows < 1) {
        os << "the camera must have at least one column and one row (got N = " << camera_columns
           << " columns, M = " << camera_rows << " rows)";
        fail(os.str());
    }
    if (display.Q < 1 || display.P < 1) {
        os << "the display must have at least one column and one row (got Q = " << display.Q << ", P = " << display.P
           << ")";
        fail(os.str());
    }
    if (!(std::isfinite(display.width) && display.width > 0 && std::isfinite(display.height) && display.height > 0)) {
        os << "the display size must be finite and positive (got " << display.width << " x " << display.height
           << " mm)";
        fail(os.str());
    }
    check_matrix(T, who);
    const std::int64_t N = camera_columns, M = camera_rows, Q = display.Q, P = display.P;
    if (T.rows != N * M) {
        os << "T has " << T.rows << " rows but the camera has N * M = " << N << " * " << M << " = " << N * M
           << " pixels";
        fail(os.str());
    }
    if (T.cols != P * Q) {
        os << "T has " << T.cols << " columns but the display has P * Q = " << P << " * " << Q << " = " << P * Q
           << " pixels";
        fail(os.str());
    }
    if (!(std::isfinite(options.threshold) && options.threshold >= 0)) {
        os << "threshold must be finite and >= 0 (got " << options.threshold << ")";
        fail(os.str());
    }
    if (!(options.energy_fraction > 0 && options.energy_fraction <= 1)) {
        os << "energy_fraction must lie in (0, 1] (got " << options.energy_fraction << ")";
        fail(os.str());
    }
    if (options.dark_block < 0 || options.dark_block > std::min(P, Q)) {
        os << "dark_block must lie in [0, min(P, Q)] = [0, " << std::min(P, Q) << "] (got " << options.dark_block
           << ")";
        fail(os.str());
    }
    if (reference_mean && reference_mean->size() != static_cast<std::size_t>(2 * N * M)) {
        os << "reference_mean has " << reference_mean->size() << " values, expected 2 per camera pixel = "
           << 2 * N * M;
        fail(os.str());
    }

    FeatureImages out;
    out.width = camera_columns;
    out.height = camera_rows;
    const auto& names = feature_channel_names(reference_mean != nullptr);
    out.channels.reserve(names.size());
    // Each channel is N * M fresh floats: from 32 MiB a channel (8.4 M pixels) its pages are
    // faulted in huge (io/Pages.h) as the zeros are written, not one small page at a time.
    for (const auto& name : names) {
        std::vector<float> channel;
        io::reserve_in_huge_pages(channel, static_cast<std::size_t>(N * M));
        channel.resize(static_cast<std::size_t>(N * M));
        out.channels.emplace_back(name, std::move(channel));
    }

    Setup s{};
    s.T = &T;
    s.Q = Q;
    s.width = display.width;
    s.height = display.height;
    s.Pd = static_cast<double>(P);
    s.Qd = static_cast<double>(Q);
    s.threshold = options.threshold;
    s.fraction = options.energy_fraction;
    const std::int64_t blk = options.dark_block;
    s.block_p0 = P / 2 - blk / 2;
    s.block_p1 = s.block_p0 + blk;
    s.block_q0 = Q / 2 - blk / 2;
    s.block_q1 = s.block_q0 + blk;
    s.reference = reference_mean;
    for (int c = 0; c < kChannelCount; ++c)
        s.out[c] = c < static_cast<int>(out.channels.size()) ? out.channels[static_cast<std::size_t>(c)].second.data()
                                                             : nullptr;

    tbb::parallel_for(tbb::blocked_range<std::int64_t>(0, T.rows, 64), [&](const tbb::blocked_range<std::int64_t>& range) {
        Scratch w;
        for (std::int64_t r = range.begin(); r != range.end(); ++r) row_features(s, r, w);
    });
    return out;
}

std::vector<float> mean_positions(const CsrMatrix& T, const std::vector<long>& rows, const DisplayGrid& display,
                                  double threshold) {
    const char* who = "mean_positions";
    auto fail = [&](const std::string& what) { throw std::invalid_argument(std::string(who) + ": " + what); };
    if (display.Q < 1 || display.P < 1 || !(std::isfinite(display.width) && display.width > 0) ||
        !(std::isfinite(display.height) && display.height > 0))
        fail("the display must have at least one column and one row and a finite, positive size");
    if (!(std::isfinite(threshold) && threshold >= 0)) fail("threshold must be finite and >= 0");
    check_matrix(T, who);
    if (T.cols != static_cast<std::int64_t>(display.P) * display.Q)
        fail("T has " + std::to_string(T.cols) + " columns but the display has P * Q = " +
             std::to_string(static_cast<std::int64_t>(display.P) * display.Q) + " pixels");
    for (const long r : rows)
        if (r < 0 || r >= T.rows) fail("row " + std::to_string(r) + " is not a row of T (" + std::to_string(T.rows) + " rows)");

    Setup s{};
    s.T = &T;
    s.Q = display.Q;
    s.width = display.width;
    s.height = display.height;
    s.Pd = static_cast<double>(display.P);
    s.Qd = static_cast<double>(display.Q);
    s.threshold = threshold;
    std::vector<float> out(2 * rows.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rows.size(), 64), [&](const tbb::blocked_range<std::size_t>& range) {
        Scratch w;
        for (std::size_t j = range.begin(); j != range.end(); ++j) {
            kept_entries(s, rows[j], w);
            double x = kNaN, y = kNaN;
            if (!w.cols.empty()) {
                w.pts.resize(w.cols.size());
                for (std::size_t i = 0; i < w.cols.size(); ++i) w.pts[i] = {w.cols[i] / s.Q, w.cols[i] % s.Q};
                const Mean m = row_mean(s, w);
                x = m.x;
                y = m.y;
            }
            out[2 * j] = static_cast<float>(x);
            out[2 * j + 1] = static_cast<float>(y);
        }
    });
    return out;
}

void add_deflection(FeatureImages& f, const std::vector<float>& ref) {
    const std::size_t n = static_cast<std::size_t>(f.width) * static_cast<std::size_t>(f.height);
    if (f.has("Deflection") || !f.has("MeanX") || !f.has("MeanY") || ref.size() != 2 * n)
        throw std::invalid_argument("add_deflection: expected features without Deflection and 2 reference values per pixel (" +
                                    std::to_string(2 * n) + "), got " + std::to_string(ref.size()));
    const std::vector<float>& mx = f.channel("MeanX");
    const std::vector<float>& my = f.channel("MeanY");
    std::vector<float> ox(n), oy(n), od(n);
    for (std::size_t k = 0; k < n; ++k) {
        double dx = static_cast<double>(mx[k]) - static_cast<double>(ref[2 * k]);
        double dy = static_cast<double>(my[k]) - static_cast<double>(ref[2 * k + 1]);
        double d = std::hypot(dx, dy);
        if (std::isnan(dx) || std::isnan(dy)) dx = dy = d = kNaN;
        ox[k] = static_cast<float>(dx);
        oy[k] = static_cast<float>(dy);
        od[k] = static_cast<float>(d);
    }
    f.channels.emplace_back("DeflectionX", std::move(ox));
    f.channels.emplace_back("DeflectionY", std::move(oy));
    f.channels.emplace_back("Deflection", std::move(od));
}

std::vector<double> apply_pattern(const CsrMatrix& T, const std::vector<float>& x) {
    check_matrix(T, "apply_pattern");
    if (static_cast<std::int64_t>(x.size()) != T.cols) {
        std::ostringstream os;
        os << "apply_pattern: the pattern has " << x.size() << " values but T has " << T.cols
           << " columns (one per display pixel)";
        throw std::invalid_argument(os.str());
    }
    std::vector<double> y(static_cast<std::size_t>(T.rows));
    T.multiply(x.data(), y.data());
    return y;
}

}  // namespace ltm
