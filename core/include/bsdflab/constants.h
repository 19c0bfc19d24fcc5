// Mathematical constants of the core, defined once (every .cpp includes this header
// rather than spelling its own pi).
#pragma once
#include <limits>

namespace bsdflab {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInvPi = 1.0 / kPi;
constexpr double kTwoPi = 2.0 * kPi; // exact: doubling a double only moves its exponent
constexpr double kDegToRad = kPi / 180.0;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

} // namespace bsdflab
