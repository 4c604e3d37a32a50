// std::lround, inlined, for the pixel loops: the library call was most of
// the time of the loops that round a coordinate per sample.
#pragma once

namespace cornerpose::internal {

// What std::lround gives (halves away from zero), for |x| < 2^23: x minus
// its truncation is exact there.
inline int RoundHalfAway(float x) {
  const int i = static_cast<int>(x);
  const float frac = x - static_cast<float>(i);
  return i + (frac >= 0.5f) - (frac <= -0.5f);
}

// The same for doubles, |x| < 2^31.
inline int RoundHalfAway(double x) {
  const int i = static_cast<int>(x);
  const double frac = x - static_cast<double>(i);
  return i + (frac >= 0.5) - (frac <= -0.5);
}

}  // namespace cornerpose::internal
