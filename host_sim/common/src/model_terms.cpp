#include "dyncal_host/common/model_terms.hpp"

#include <sstream>

namespace dyncal::host {

unsigned parse_model(const std::string& model) {
  unsigned terms = 0;
  std::stringstream ss(model);
  std::string item;
  while (std::getline(ss, item, ',')) {
    if (item == "eq7")
      terms |= kFrictionEq7;
    else if (item == "eq8")
      terms |= kFrictionEq8;
    else if (item == "coulomb")
      terms |= term::coulomb;
    else if (item == "viscous")
      terms |= term::viscous;
    else if (item == "power")
      terms |= term::power;
    else if (item == "rotor_inertia" || item == "ia")
      terms |= term::rotor_inertia;
    else if (item == "offset")
      terms |= term::offset;
    else if (item == "rigid_body" || item.empty())
      continue;
    else if (item.find(':') != std::string::npos) {
      throw InputError("model item '" + item + "': effect terms are taken by identify, diagnose and predict, not here");
    } else {
      throw InputError("unknown model term '" + item +
                       "' (expected eq7, eq8, coulomb, viscous, power, rotor_inertia, offset, or an effect "
                       "KIND:JOINT[:SHAPE])");
    }
  }
  return terms;
}

std::string model_name(unsigned terms) {
  std::string out = "rigid_body";
  const char* names[] = {"coulomb", "viscous", "power", "load", "rotor_inertia", "offset"};
  for (int i = 0; i < kNumTerms; ++i) {
    if (terms & term_bit(i)) out += std::string(",") + names[i];
  }
  return out;
}

int built_term_set_index(unsigned terms) {
  for (int i = 0; i < kBuiltTermSets; ++i)
    if (built_term_set(i) == terms) return i;
  throw InputError("model '" + model_name(terms) +
                   "' is not built: use Coulomb + viscous (eq7) or eq8, optionally with rotor_inertia and offset");
}

}  // namespace dyncal::host
