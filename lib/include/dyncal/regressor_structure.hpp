#pragma once

#include <cstdint>

namespace dyncal {

/// Structural sparsity of a measurement matrix H (N x P), such as the identification regressor:
/// column c can be nonzero only in rows first[c]..last[c] (0-based; first > last marks a column
/// that is always zero). The six-axis regressor is block triangular: a link's base parameters act
/// on its own joint and the joints before it (rows 0..link), a joint's friction terms on that
/// joint only. Estimators use it to skip structural zeros; they check every update that H has no
/// nonzero entry outside it.
template <int P>
struct RegressorStructure {
  std::int8_t first[P];
  std::int8_t last[P];

  /// Every column may be nonzero in every one of the N rows.
  static constexpr RegressorStructure dense(int N) noexcept {
    RegressorStructure s{};
    for (int c = 0; c < P; ++c) {
      s.first[c] = 0;
      s.last[c] = static_cast<std::int8_t>(N - 1);
    }
    return s;
  }
};

/// Writes the generated base-regressor structure of Robot (Robot::base_column_first_row /
/// last_row) into columns 0..Robot::kNumBase-1 of `s`.
template <class Robot, int P>
constexpr void set_base_structure(RegressorStructure<P>& s) noexcept {
  static_assert(P >= Robot::kNumBase, "structure narrower than the base regressor");
  for (int c = 0; c < Robot::kNumBase; ++c) {
    s.first[c] = static_cast<std::int8_t>(Robot::base_column_first_row(c));
    s.last[c] = static_cast<std::int8_t>(Robot::base_column_last_row(c));
  }
}

}  // namespace dyncal
