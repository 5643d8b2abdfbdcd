#pragma once
// Numbers for defect images: regions of camera pixels, the contrast-to-noise ratio of a defect
// against its surround, and a robust count of outlying pixels (false positives in a defect-free
// image).
//
// Images are camera images in the conventions' order (docs: docs/conventions.md): width
// N columns, height M rows, pixel (m, n) at index k = m * N + n, row 0 the top (+y) edge.
// Positions (cx, cy) are in pixel units on the image's own axes: x to the right along columns,
// y DOWN along rows, the top-left corner of the image at (0, 0), so camera pixel (m, n) is the
// unit square [n, n + 1] x [m, m + 1] with its centre at (n + 0.5, m + 0.5).
#include <string>
#include <vector>

namespace ltm {

// A set of camera pixels. The functions below return the indices k in increasing order, each
// once; the statistics below use whatever a Region holds (a pixel listed twice counts twice).
struct Region {
    std::vector<int> pixels;  // camera pixel indices k = m * width + n
};

// The pixels whose CENTRES lie within `radius` of (cx, cy): (n + 0.5 - cx)^2 + (m + 0.5 - cy)^2
// <= radius^2 (inclusive, evaluated in double), clipped to the image. A disc of radius 0.5 (or 0)
// around a pixel centre is exactly that pixel. width, height >= 0, radius >= 0 and finite
// centres, else std::invalid_argument.
Region disc_region(int width, int height, double cx, double cy, double radius);

// The pixels whose centres lie at a distance d with r_in < d <= r_out (d^2 and the radii squared
// compared in double, as disc_region): exactly subtract(disc_region(.., r_out),
// disc_region(.., r_in)). 0 <= r_in <= r_out, else std::invalid_argument.
Region annulus_region(int width, int height, double cx, double cy, double r_in, double r_out);

// The pixels of a that are not in b, in a's order.
Region subtract(const Region& a, const Region& b);

// CNR >= this shows a defect: the Rose criterion, a contrast of 5 standard deviations for certain
// detection (A. Rose, "Vision: Human and Electronic", 1973). The experiment's best new feature and
// acquire's `visible` both use it.
constexpr double kVisibleCnr = 5.0;

struct ContrastResult {
    double defect_mean = 0, surround_mean = 0, surround_std = 0, cnr = 0;
    double noise = 0;  // what the contrast is divided by: max(surround_std, resolution / sqrt 12)
    int defect_pixels = 0, surround_pixels = 0;  // finite pixels used
};

// Contrast-to-noise ratio CNR = |mean(defect) - mean(surround)| / noise, all in double (two
// passes: the mean, then the squared deviations). The noise is the surround's sample standard
// deviation (divisor n - 1), but never less than resolution / sqrt 12: an image cannot show a
// spread finer than the step q = `resolution` its values are resolved to, and a surround whose
// pixels all read the same value has a spread below that step. q / sqrt 12 is the standard
// deviation of a rounding error spread uniformly over one step, the standard uncertainty the GUM
// assigns to an indication of resolution q (JCGM 100:2008, F.2.2.1). Without it (resolution 0) a
// noise-free surround (std == 0) gives cnr = +inf when the means differ and 0 when they are equal
// (no contrast, no noise: nothing to see). NaN (and +-inf) pixels are excluded; the counts are of
// the finite pixels used. A defect region with no finite pixel, a surround with fewer than 2, an
// index outside the image, or a resolution that is negative or not finite, is
// std::invalid_argument.
ContrastResult contrast_to_noise(const std::vector<float>& image, const Region& defect, const Region& surround,
                                 double resolution = 0);

// The step q each kind of feature value is resolved to (contrast_to_noise's `resolution`), by the
// unit features/Features.h gives its channel: fractions of a pixel's light (BrightField,
// DarkField), positions in mm (MeanX/Y, Deflection*), extents between display pixel centres
// (ScatterRows, ScatterColumns, ScatterDiameter, RobustScatterDiameter), counts, display indices
// (ScatterWidth) and angles in degrees (EllipseAngle); the widths of the second-moment ellipse
// (EllipseMajor, EllipseMinor), display pixels too, are energy-weighted moments and resolve as
// finely as a mean position does: `moment`. A rendered image and a measured one resolve
// different steps; whoever makes the image says which (study/Experiment.h, acquire/Instrument.h).
struct Resolution {
    double fraction = 0, mm = 0, moment = 0, display_pixels = 1, count = 1, index = 1, degrees = 1;
    // The step for `channel`; 0 for a channel without a unit.
    double of(const std::string& channel) const;
};

// 1 / Phi^-1(3/4) = 1.482602...: for Gaussian data, 1.4826 MAD is a consistent estimate of the
// standard deviation (F. R. Hampel, "The influence curve and its role in robust estimation",
// JASA 69 (1974) 383-393; P. J. Rousseeuw and C. Croux, "Alternatives to the median absolute
// deviation", JASA 88 (1993) 1273-1283).
constexpr double kMadToSigma = 1.4826;

// The number of pixels in `valid` that deviate from the median of the valid pixels by more than
// k * 1.4826 * MAD, MAD = median |x - median| (the median of an even count is the mean of the two
// middle values): a k-sigma outlier test with the noise estimated robustly. Non-finite pixels:
// NaN is excluded (neither tested nor part of the median); +-inf takes part like any value (so it
// counts, unless infinities make up half the region).
//
// Why robust: the pixels we count are exactly the outliers, and a mean and standard deviation
// would be pulled by them: m spikes of height h among n pixels inflate the standard deviation to
// about sqrt(sigma^2 + m h^2 / n), so their own z-score stays below ~sqrt(n / m) however large h
// is (masking: with many outliers, or few pixels, none is found). The median and MAD
// have a 50% breakdown point: up to half the pixels can be arbitrary without moving them far, so
// the threshold reflects the noise of the clean pixels only (see also C. Leys et al., "Detecting
// outliers: Do not use standard deviation around the mean, use absolute deviation around the
// median", J. Exp. Soc. Psychol. 49 (2013) 764-766).
//
// MAD == 0 (more than half the valid pixels share one value, e.g. a noise-free rendering): the
// threshold is 0 and, with the strict comparison, every pixel that differs from the median counts.
// An empty region (or one with only NaN) gives 0. k must be finite and >= 0, else
// std::invalid_argument; an index outside the image is std::invalid_argument.
int false_positives(const std::vector<float>& image, const Region& valid, double k = 5.0);

}  // namespace ltm
