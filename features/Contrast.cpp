// Contrast.h: pixel regions, contrast-to-noise ratio, robust outlier counts.
#include "features/Contrast.h"

#include "features/Features.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace ltm {

namespace {

void check_size(int width, int height, const char* who) {
    if (width < 0 || height < 0)
        throw std::invalid_argument(std::string(who) + ": image size " + std::to_string(width) + " x " +
                                    std::to_string(height) + " is negative");
}

// Columns (or rows) whose centres i + 0.5 can lie within r of c, clipped to [0, count - 1], with
// one spare on each side so rounding never drops a pixel (the exact test decides).
std::pair<int, int> candidate_span(double c, double r, int count) {
    const double first = std::floor(c - r - 0.5) - 1, last = std::ceil(c - 0.5 + r) + 1;
    const int a = static_cast<int>(std::clamp(first, 0.0, static_cast<double>(count)));
    const int b = static_cast<int>(std::clamp(last, -1.0, static_cast<double>(count - 1)));
    return {a, b};
}

// Pixels with r_in^2 < d^2 <= r_out^2 (r_in < 0: no inner exclusion, i.e. a disc).
Region ring(int width, int height, double cx, double cy, double r_in, double r_out) {
    Region region;
    const auto [m0, m1] = candidate_span(cy, r_out, height);
    const auto [n0, n1] = candidate_span(cx, r_out, width);
    const double out2 = r_out * r_out, in2 = r_in < 0 ? -1.0 : r_in * r_in;
    for (int m = m0; m <= m1; ++m)
        for (int n = n0; n <= n1; ++n) {
            const double dx = n + 0.5 - cx, dy = m + 0.5 - cy;
            const double d2 = dx * dx + dy * dy;
            if (d2 <= out2 && d2 > in2) region.pixels.push_back(m * width + n);
        }
    return region;
}

void check_centre(double cx, double cy, const char* who) {
    if (!std::isfinite(cx) || !std::isfinite(cy))
        throw std::invalid_argument(std::string(who) + ": the centre must be finite");
}

void check_index(int k, std::size_t size, const char* who) {
    if (k < 0 || static_cast<std::size_t>(k) >= size)
        throw std::invalid_argument(std::string(who) + ": pixel index " + std::to_string(k) +
                                    " is outside the image (" + std::to_string(size) + " pixels)");
}

struct Moments {
    double mean = 0, std = 0;
    int count = 0;
};

// Mean and sample standard deviation (0 for one pixel) of the finite pixels of a region (two
// passes); at least `least` of them.
Moments moments(const std::vector<float>& image, const Region& region, const char* name, std::size_t least) {
    std::vector<double> v;
    v.reserve(region.pixels.size());
    for (const int k : region.pixels) {
        check_index(k, image.size(), "contrast_to_noise");
        const float x = image[static_cast<std::size_t>(k)];
        if (std::isfinite(x)) v.push_back(x);
    }
    if (v.size() < least)
        throw std::invalid_argument(std::string("contrast_to_noise: the ") + name + " region has " +
                                    std::to_string(v.size()) + " finite pixels; at least " + std::to_string(least) +
                                    (least == 1 ? " is" : " are") + " needed");
    Moments mo;
    mo.count = static_cast<int>(v.size());
    double sum = 0;
    for (const double x : v) sum += x;
    mo.mean = sum / static_cast<double>(v.size());
    double ss = 0;
    for (const double x : v) ss += (x - mo.mean) * (x - mo.mean);
    mo.std = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
    return mo;
}

// The median of v (reordered); the mean of the two middle values for an even count; v non-empty.
double median(std::vector<double>& v) {
    const std::size_t h = v.size() / 2;
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h), v.end());
    const double upper = v[h];
    if (v.size() % 2 == 1) return upper;
    const double lower = *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(h));
    if (lower == upper) return upper;    // also for two equal infinities
    return lower + (upper - lower) / 2;  // no overflow
}

}  // namespace

Region disc_region(int width, int height, double cx, double cy, double radius) {
    check_size(width, height, "disc_region");
    check_centre(cx, cy, "disc_region");
    if (!(radius >= 0) || std::isinf(radius))
        throw std::invalid_argument("disc_region: the radius must be finite and >= 0");
    return ring(width, height, cx, cy, -1.0, radius);
}

Region annulus_region(int width, int height, double cx, double cy, double r_in, double r_out) {
    check_size(width, height, "annulus_region");
    check_centre(cx, cy, "annulus_region");
    if (!(r_in >= 0) || !(r_out >= r_in) || std::isinf(r_out))
        throw std::invalid_argument("annulus_region: the radii must satisfy 0 <= r_in <= r_out < inf");
    return ring(width, height, cx, cy, r_in, r_out);
}

Region subtract(const Region& a, const Region& b) {
    std::vector<int> remove = b.pixels;
    std::sort(remove.begin(), remove.end());
    Region out;
    for (const int k : a.pixels)
        if (!std::binary_search(remove.begin(), remove.end(), k)) out.pixels.push_back(k);
    return out;
}

ContrastResult contrast_to_noise(const std::vector<float>& image, const Region& defect, const Region& surround,
                                 double resolution) {
    if (!(resolution >= 0) || std::isinf(resolution))
        throw std::invalid_argument("contrast_to_noise: the resolution must be finite and >= 0");
    const Moments d = moments(image, defect, "defect", 1);
    const Moments s = moments(image, surround, "surround", 2);
    ContrastResult r;
    r.defect_mean = d.mean;
    r.surround_mean = s.mean;
    r.surround_std = s.std;
    r.noise = std::max(s.std, resolution / std::sqrt(12.0));
    r.defect_pixels = d.count;
    r.surround_pixels = s.count;
    const double diff = std::fabs(d.mean - s.mean);
    if (r.noise > 0) r.cnr = diff / r.noise;
    else r.cnr = diff > 0 ? std::numeric_limits<double>::infinity() : 0.0;
    return r;
}

double Resolution::of(const std::string& channel) const {
    if (channel == "EllipseMajor" || channel == "EllipseMinor") return moment;
    const std::string unit = feature_unit(channel);
    if (unit == "fraction") return fraction;
    if (unit == "mm") return mm;
    if (unit == "display pixels") return display_pixels;
    if (unit == "count") return count;
    if (unit == "index") return index;
    if (unit == "degrees") return degrees;
    return 0;
}

int false_positives(const std::vector<float>& image, const Region& valid, double k) {
    if (!(k >= 0) || std::isinf(k)) throw std::invalid_argument("false_positives: k must be finite and >= 0");
    std::vector<double> v;
    v.reserve(valid.pixels.size());
    for (const int i : valid.pixels) {
        check_index(i, image.size(), "false_positives");
        const float x = image[static_cast<std::size_t>(i)];
        if (!std::isnan(x)) v.push_back(x);
    }
    if (v.empty()) return 0;
    std::vector<double> work = v;
    const double med = median(work);
    for (std::size_t i = 0; i < v.size(); ++i) work[i] = std::fabs(v[i] - med);
    const double mad = median(work);
    const double threshold = k * kMadToSigma * mad;
    int count = 0;
    for (const double x : v)
        if (std::fabs(x - med) > threshold) ++count;
    return count;
}

}  // namespace ltm
