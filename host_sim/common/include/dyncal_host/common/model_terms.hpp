#pragma once
// The identification model's vocabulary (dyncal::term bits by name), the term sets compiled into
// the host tools, and the one switch that maps a runtime term set to a compile-time one.

#include <string>
#include <utility>

#include "dyncal/friction.hpp"
#include "dyncal_host/common/input_error.hpp"

namespace dyncal::host {

/// Parses a model string: comma-separated terms (coulomb, viscous, power, rotor_inertia, offset)
/// and aliases eq7 (= coulomb,viscous) and eq8 (= eq7,power). Throws InputError.
unsigned parse_model(const std::string& model);
/// "rigid_body" followed by the terms of `terms`, comma-separated, in the column order.
std::string model_name(unsigned terms);

/// Eq. 7 or Eq. 8 friction, each with or without rotor inertia and offset.
constexpr bool is_built_term_set(unsigned terms) {
  const unsigned optional = term::rotor_inertia | term::offset;
  const unsigned friction = terms & ~optional;
  return friction == kFrictionEq7 || friction == kFrictionEq8;
}

/// Number of built term sets, and the i-th of them (0-based; Eq. 7 ones first).
inline constexpr int kBuiltTermSets = 8;
constexpr unsigned built_term_set(int i) {
  const unsigned friction = i < 4 ? kFrictionEq7 : kFrictionEq8;
  return friction | ((i & 1) ? term::rotor_inertia : 0u) | ((i & 2) ? term::offset : 0u);
}
/// Index of a built term set (built_term_set(index) == terms). Throws InputError naming the model
/// when it is not built.
int built_term_set_index(unsigned terms);

/// Calls F<Terms>::run(args...) for the compiled term set equal to `terms`. Throws InputError naming
/// the model when it is not built.
template <template <unsigned> class F, typename... Args>
decltype(auto) with_term_set(unsigned terms, Args&&... args) {
  constexpr unsigned ia = term::rotor_inertia, off = term::offset;
  switch (terms) {
    case kFrictionEq7:
      return F<kFrictionEq7>::run(std::forward<Args>(args)...);
    case kFrictionEq7 | ia:
      return F<kFrictionEq7 | ia>::run(std::forward<Args>(args)...);
    case kFrictionEq7 | off:
      return F<kFrictionEq7 | off>::run(std::forward<Args>(args)...);
    case kFrictionEq7 | ia | off:
      return F<kFrictionEq7 | ia | off>::run(std::forward<Args>(args)...);
    case kFrictionEq8:
      return F<kFrictionEq8>::run(std::forward<Args>(args)...);
    case kFrictionEq8 | ia:
      return F<kFrictionEq8 | ia>::run(std::forward<Args>(args)...);
    case kFrictionEq8 | off:
      return F<kFrictionEq8 | off>::run(std::forward<Args>(args)...);
    case kFrictionEq8 | ia | off:
      return F<kFrictionEq8 | ia | off>::run(std::forward<Args>(args)...);
    default:
      throw InputError("model '" + model_name(terms) +
                       "' is not built: use Coulomb + viscous (eq7) or eq8, optionally with rotor_inertia and offset");
  }
}

}  // namespace dyncal::host
