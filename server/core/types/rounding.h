#pragma once

#include <type_traits>

namespace objmap {

/// std::lround for 0 <= x < 2^23 (depth in millimetres, colour channels) without its library
/// call, which costs more than the rest of a per-pixel loop. Exact in that range: x + 0.5 is
/// computed without rounding for x >= 0.5, and below 0.5 the answer is 0 (adding 0.5 to the
/// largest float under 0.5 would round up to 1).
template <typename Real>
[[nodiscard]] inline long RoundNonNegative(Real x) {
  static_assert(std::is_floating_point_v<Real>);
  return x < Real(0.5) ? 0 : static_cast<long>(x + Real(0.5));
}

}  // namespace objmap
