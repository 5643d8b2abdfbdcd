#pragma once
// Features of the rows of a light transport matrix T: one value per camera pixel, computed from
// that pixel's correspondence vector (its row of T, the display pixels it sees and how much).
//
// Indices (docs: docs/conventions.md, "Pixel indices"): row k = m * N + n is camera pixel
// (m, n), column l = p * Q + q is display pixel (p, q); rows m and p count from the +y (top) edge
// down, columns n and q from the -x edge. Feature images are camera-sized, row-major, row 0 on top
// (the io/Image.h orientation), so they can go straight to write_exr.
//
// The contributing set of a row: its stored entries with value > threshold (the paper's eq. 3
// "c_i >= 0" read as "> threshold"; threshold 0 keeps the entries > 0, so explicit zeros and
// negative values never count). Every feature except BrightField and DarkField is computed over
// this set; BrightField and DarkField are the plain products T x and see every stored entry.
//
// Channels, in this order (exact names; FeatureImages::channels):
//  BrightField        y = T 1: the row sum, the telecentric bright-field image (all display pixels on).
//  DarkField          y = T x, x = 0 on a centred block of dark_block x dark_block display pixels,
//                     1 elsewhere. The block covers rows p in [P/2 - b/2, P/2 - b/2 + b) and columns
//                     q in [Q/2 - b/2, Q/2 - b/2 + b) (integer division, b = dark_block): exactly
//                     centred when b and P (Q) have the same parity; otherwise half a pixel off,
//                     towards the top (left) for odd P (Q), the bottom (right) for even P (Q).
//                     b = 0 gives BrightField, b = min(P, Q) a dark band across the display.
//  ScatterCount       eq. 3: the number of contributing entries.
//  ScatterWidth       eq. 4: last - first linear display index l of the contributing entries
//                     (0 when there are none or one).
//  ScatterRows        p_max - p_min over the contributing entries (0 if none).
//  ScatterColumns     q_max - q_min over the contributing entries (0 if none).
//  ScatterDiameter    the largest Euclidean distance, in display pixels (steps of one row or one
//                     column: not mm, pixels need not be square), between the centres of two
//                     contributing display pixels; exact: the convex hull (Andrew's monotone
//                     chain, integer arithmetic) and the largest distance over its vertex pairs.
//                     0 for fewer than two entries.
//  EllipseMajor,      the second-moment ellipse of the row's energy on the display: weights are
//  EllipseMinor,      the contributing values, positions the pixel centres in display pixels as
//  EllipseAngle       (x, y) = (q, -p) (x to the right, y UP). Major and minor are 2 sqrt of the
//                     eigenvalues of the weighted covariance, i.e. the full widths at one standard
//                     deviation (for a uniform segment of length L the major is L / sqrt 3). The
//                     angle of the major axis is in degrees, counter-clockwise from the display's
//                     +x axis, in (-90, 90]; 0 for a circular ellipse. An empty row gives 0, 0, 0
//                     (no energy: no extent, the same as a single pixel; see MeanX for emptiness).
//  RobustScatterCount,    ScatterCount and ScatterDiameter over the smallest set of contributing
//  RobustScatterDiameter  entries that holds at least energy_fraction of the row's energy: sorted
//                     by value descending (ties by column ascending), taken until the running sum
//                     (double) is >= energy_fraction x total, where the total is summed in the same
//                     order (so energy_fraction = 1 takes every entry). They ignore the rare
//                     far-off Monte Carlo paths that make the paper's "white dots" in ScatterWidth.
//  MeanX, MeanY       the energy-weighted mean display position in mm (display coordinates: pixel
//                     (p, q) has its centre at x = -W/2 + (q + 0.5) W/Q, y = H/2 - (p + 0.5) H/P);
//                     NaN for an empty row.
// With a reference (the defect-free object's MeanX, MeanY per camera pixel):
//  DeflectionX,       mean - reference in mm (MeanX, MeanY as stored, in float, minus the
//  DeflectionY,       reference: a row whose means equal the reference's gives exactly 0), and
//                     its length; NaN where the row is empty or the reference is NaN.
//  Deflection
//
// Every per-row quantity is computed in double and stored as float (counts and index differences
// are exact below 2^24). Rows are processed in parallel (TBB); each value depends on its own row
// only, so the result is bit-identical whatever the number of threads.
#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "io/CsrMatrix.h"

namespace ltm {

// The display: Q columns, P rows, width x height in mm, centred on the optical axis.
struct DisplayGrid {
    int Q = 0, P = 0;
    double width = 0, height = 0;
};

struct FeatureOptions {
    double threshold = 0.0;         // entries > threshold contribute; finite, >= 0
    double energy_fraction = 0.99;  // Robust*: fraction of the row's energy kept, in (0, 1]
    int dark_block = 60;            // DarkField: side of the dark centred block, in [0, min(P, Q)]
};

// The DarkField block that an automatic dark_block (< 0, as render, dataset and experiment leave
// it) stands for on `display`: 60 display pixels, or the display's smaller side if less. An
// acquisition measures the dark field with the same block.
inline int automatic_dark_block(const DisplayGrid& display) { return std::min({60, display.P, display.Q}); }

struct FeatureImages {
    int width = 0, height = 0;  // camera columns N and rows M
    std::vector<std::pair<std::string, std::vector<float>>> channels;  // width * height values each

    // The channel called `name`; std::out_of_range naming it (and the channels there are) if absent.
    bool has(const std::string& name) const {
        for (const auto& c : channels)
            if (c.first == name) return true;
        return false;
    }
    const std::vector<float>& channel(const std::string& name) const;
};

// The channel names compute_features produces, in order (with_reference: the Deflection* three
// at the end).
const std::vector<std::string>& feature_channel_names(bool with_reference);

// The unit of a channel's values, as docs/features.md lists it ("fraction", "count", "index",
// "display pixels", "degrees", "mm"); "" for a name that is not a feature channel.
std::string feature_unit(const std::string& channel);

// A figure title for a channel: "ScatterCount (count)"; the bare name if it has no unit.
std::string feature_title(const std::string& channel);

// All features of every row of T (see above). camera_columns = N, camera_rows = M.
// reference_mean (optional): 2 floats per camera pixel, (x, y) in mm, in camera pixel order, the
// mean display position of the defect-free object's row (NaN where that row is empty).
// Throws std::invalid_argument, with a message naming the problem, unless: T is a valid CSR
// matrix (CsrMatrix::check), N, M, P, Q >= 1, width and height finite and > 0, T.rows == N * M,
// T.cols == P * Q, threshold finite and >= 0, 0 < energy_fraction <= 1,
// 0 <= dark_block <= min(P, Q), and reference_mean (if given) has 2 N M values.
FeatureImages compute_features(const CsrMatrix& T, int camera_columns, int camera_rows, const DisplayGrid& display,
                               const FeatureOptions& options, const std::vector<float>* reference_mean = nullptr);

// MeanX and MeanY of the given rows of T only, as (x, y) pairs in the order of `rows`: the
// values compute_features gives those rows with this threshold (the same arithmetic, shared), NaN
// for a row with no entry above it. For a reference render that traced a few of the camera's
// pixels: all channels of every pixel would be 56 MB of fresh pages at industrial scale for the
// two values of a few thousand rows. Throws std::invalid_argument unless T is a valid CSR matrix
// (CsrMatrix::check) with P * Q columns, the display is as compute_features requires, the
// threshold is finite and >= 0 and every row is one of T's.
std::vector<float> mean_positions(const CsrMatrix& T, const std::vector<long>& rows, const DisplayGrid& display,
                                  double threshold);

// Appends DeflectionX, DeflectionY and Deflection to features computed without a reference, from
// their MeanX and MeanY: exactly the values compute_features gives with `reference_mean`.
// Throws std::invalid_argument if the channels are already there or the sizes do not match.
void add_deflection(FeatureImages& features, const std::vector<float>& reference_mean);

// y = T x (CsrMatrix::multiply: each y[k] accumulated in double in column order, deterministic).
// Throws std::invalid_argument if x does not have T.cols values or T is not a valid CSR matrix.
std::vector<double> apply_pattern(const CsrMatrix& T, const std::vector<float>& x);

}  // namespace ltm
