#pragma once
// Every feature channel as an instrument measures it: the pattern family and count each feature
// needs (docs/acquisition.md, "Each feature as an instrument measures it"), run through the
// sensor model, so that `ltmsim experiment` can judge every image by the contrast a measurement
// could show, not only by the rendered T's.
//
//   channels                                          method        K (500 x 500 display)
//   BrightField                                       bright field  1: the exposure every acquisition
//                                                                   takes beside its patterns
//                                                                   (AcquireResult::bright), the one
//                                                                   `acquire` judges CNRs against
//   DarkField                                         fields        2: the bright and the dark field
//   MeanX, MeanY (and the deflection map from them)   gray          2 (nq + np) + 6 = 42: the Gray code
//                                                                   locates a row's display pixel, three
//                                                                   phase steps per axis (the fewest
//                                                                   that cancel the constant parts) its
//                                                                   sub-pixel mean
//   ScatterRows, ScatterColumns                       stripes       P + Q = 1000: line scans (w = 1), the
//                                                                   extents in whole display pixels as
//                                                                   they are defined
//   ScatterCount, ScatterWidth, ScatterDiameter,      compressive   126 + 1024 = 1150: screening stripes of
//   Ellipse*, RobustScatter*                                        8 display pixels (ceil(P / 8) +
//                                                                   ceil(Q / 8)) and 1024 Bernoulli
//                                                                   patterns, the largest count of
//                                                                   docs/acquisition.md's sweep, where
//                                                                   the recovered counts are within 1 of
//                                                                   T's (median) and the noise-free
//                                                                   recovery gives every row; a display
//                                                                   of no more pixels than that is
//                                                                   measured by brute force (P Q
//                                                                   patterns, no more)
//
// The deflection map needs the defect-free object's means as well; the caller subtracts its
// reference (add_deflection), as `acquire` does.
#include <map>
#include <string>
#include <vector>

#include "acquire/Acquisition.h"
#include "features/Contrast.h"

namespace ltm::acquire {

// The acquisition `channel` is measured with on a P x Q display (see above): method and K in
// the options, the rest at their defaults. std::invalid_argument for a channel not listed.
AcquireOptions instrument_for(const std::string& channel, int P, int Q);

// "gray (K = 42)": a method and its pattern count, for tables (no comma: it is a CSV field).
std::string describe(const AcquireOptions& o);

// The step q each channel's measured values resolve (features/Contrast.h): a fraction of light to
// one ADC step of the calibrated measurement, 1 / ((2^bits - 1) exposure); a phase-shifted
// position to the shift one ADC step gives a sinusoid of half the row's light, period x pitch x
// step / pi; an ellipse width (a moment of recovered weights) to that step in display pixels;
// extents, counts and indices to 1 (the stripes' width for a stripe scan); angles to 1 degree.
double measured_resolution(const std::string& channel, const AcquireOptions& o, const SensorModel& sensor,
                           const DisplayGrid& display);

struct InstrumentImages {
    FeatureImages features;                     // every channel of the table above
    std::map<std::string, std::string> how;     // channel -> describe(its options)
    std::map<std::string, double> resolution;   // channel -> measured_resolution
};

// Every channel measured as instrument_for says, each method run once (its images give all the
// channels it measures). Bit-identical for a given sensor seed whatever `threads`.
InstrumentImages measure_features(const CsrMatrix& T, int camera_columns, int camera_rows, const DisplayGrid& display,
                                  const SensorModel& sensor, int threads);

}  // namespace ltm::acquire
