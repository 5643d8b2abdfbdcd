// Real roots of polynomials of degree <= 4 (trace/Polynomial.h) against polynomials built from
// known roots: every simple root in the interval is found once, to the accuracy its condition
// allows; roots of even multiplicity (touching, no sign change) are not crossings.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "tests/Tolerances.h"
#include "trace/Polynomial.h"

using namespace ltm;

namespace {

// The coefficients (ascending) of lead * prod (x - r_i).
std::vector<double> from_roots(const std::vector<double>& roots, double lead = 1.0) {
    std::vector<double> c{lead};
    for (double r : roots) {
        std::vector<double> n(c.size() + 1, 0.0);
        for (size_t i = 0; i < c.size(); ++i) {
            n[i + 1] += c[i];
            n[i] -= r * c[i];
        }
        c = n;
    }
    return c;
}

double abs_sum(const std::vector<double>& c, double x) {
    double s = 0, p = 1;
    for (double ci : c) {
        s += std::fabs(ci) * p;
        p *= std::fabs(x);
    }
    return s;
}

void expect_roots(const std::vector<double>& c, double lo, double hi, std::vector<double> expected) {
    const int degree = static_cast<int>(c.size()) - 1;
    const PolyRoots r = real_roots(c.data(), degree, lo, hi);
    std::sort(expected.begin(), expected.end());
    ASSERT_EQ(r.count, static_cast<int>(expected.size())) << "lo " << lo << " hi " << hi;
    for (int i = 0; i < r.count; ++i) {
        const double x = expected[static_cast<size_t>(i)];
        const double slope = poly_derivative(c.data(), degree, x);
        EXPECT_NEAR(r.x[static_cast<size_t>(i)], x, tol::poly_root(degree, abs_sum(c, x), slope)) << "root " << i;
    }
}

}  // namespace

TEST(Polynomial, QuarticWithFourSimpleRoots) {
    const auto c = from_roots({1, 2, 3, 4});
    expect_roots(c, 0, 10, {1, 2, 3, 4});
    expect_roots(c, 1.5, 3.5, {2, 3});
    expect_roots(c, 4.5, 9, {});
}

TEST(Polynomial, CubicAndQuadraticAndLinear) {
    expect_roots(from_roots({-1, 0.5, 7}, 3.0), -10, 10, {-1, 0.5, 7});
    expect_roots(from_roots({-2, 5}, -0.25), -10, 10, {-2, 5});
    expect_roots(from_roots({1.25}, 4.0), -10, 10, {1.25});
}

TEST(Polynomial, ExactZeroLeadingCoefficientsLowerTheDegree) {
    auto c = from_roots({-3, 2});  // degree 2, padded to degree 4 with zeros
    c.push_back(0.0);
    c.push_back(0.0);
    const PolyRoots r = real_roots(c.data(), 4, -10, 10);
    ASSERT_EQ(r.count, 2);
    EXPECT_DOUBLE_EQ(r.x[0], -3);
    EXPECT_DOUBLE_EQ(r.x[1], 2);
}

TEST(Polynomial, DoubleRootsTouchWithoutCrossing) {
    // (x - 1)^2 (x - 3)(x - 4): the tangency at 1 is no crossing.
    expect_roots(from_roots({1, 1, 3, 4}), 0, 10, {3, 4});
    // (x - 2)^2 (x^2 + 1): no crossing at all.
    std::vector<double> c = from_roots({2, 2});
    std::vector<double> q(5, 0.0);
    for (size_t i = 0; i < c.size(); ++i) {
        q[i] += c[i];
        q[i + 2] += c[i];
    }
    EXPECT_EQ(real_roots(q.data(), 4, -10, 10).count, 0);
}

TEST(Polynomial, CloseRootsAreSeparated) {
    // Two crossings 1e-6 apart (a chord of a grazing ray) are both found: the critical point
    // between them splits the interval.
    expect_roots(from_roots({1.0, 1.0 + 1e-6, 5, 6}), 0, 10, {1.0, 1.0 + 1e-6, 5, 6});
    expect_roots(from_roots({-1e-3, 1e-3}, 1.0), -1, 1, {-1e-3, 1e-3});
}

TEST(Polynomial, RootsAtTheIntervalEndsAreIncluded) {
    expect_roots(from_roots({0, 2, 5}), 0, 5, {0, 2, 5});
}

TEST(Polynomial, RandomQuarticsAgreeWithTheirConstruction) {
    // Seeded random quartics with well-separated roots at scales 1e-3..1e3.
    std::mt19937_64 gen(7);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int trial = 0; trial < 2000; ++trial) {
        const double scale = std::pow(10.0, 6.0 * (0.5 + 0.5 * u(gen)) - 3.0);
        std::vector<double> roots;
        while (roots.size() < 4) {
            const double r = scale * u(gen);
            bool far = true;
            for (double s : roots) far = far && std::fabs(s - r) > 1e-3 * scale;
            if (far) roots.push_back(r);
        }
        const auto c = from_roots(roots, u(gen) > 0 ? 1.0 : -2.5);
        expect_roots(c, -2 * scale, 2 * scale, roots);
    }
}
