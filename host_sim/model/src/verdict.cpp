#include "dyncal_host/model/verdict.hpp"

#include <cmath>

namespace dyncal::host {

Verdict verdict_of(double std, double scale) {
  if (!std::isfinite(std) || !(kVerdictZ * std <= scale)) return Verdict::not_determined;
  return kVerdictZ * std <= kDeterminedFraction * scale ? Verdict::determined : Verdict::poorly_determined;
}

const char* to_string(Verdict v) {
  switch (v) {
    case Verdict::determined:
      return "determined";
    case Verdict::poorly_determined:
      return "poorly determined";
    case Verdict::not_determined:
      return "not determined";
  }
  return "?";
}

}  // namespace dyncal::host
