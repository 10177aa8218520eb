#pragma once
// A parameter's verdict: whether a log determines it, from its standard deviation and physical scale
// (docs/accuracy.md, "Real arms"; the rule that decides it: identification/methods/identifiability.hpp).

#include "dyncal_host/common/normal_quantile.hpp"

namespace dyncal::host {

/// A parameter's 95 % confidence interval is value +- kVerdictZ std (normal_quantile.hpp).
inline constexpr double kVerdictZ = kZ95;
/// "determined" when the 95 % interval's half width is at most this fraction of the parameter's
/// physical scale: the log fixes the parameter to a tenth of its plausible size.
inline constexpr double kDeterminedFraction = 0.1;

/// A parameter's verdict from its standard deviation `std` and physical scale `scale` (> 0):
/// determined: kVerdictZ std <= kDeterminedFraction scale; not determined: kVerdictZ std > scale
/// (the 95 % interval is wider than the parameter's plausible size: the log does not fix even its
/// order of magnitude); poorly determined in between. A non-finite std is not determined.
enum class Verdict { determined, poorly_determined, not_determined };
Verdict verdict_of(double std, double scale);
/// "determined", "poorly determined", "not determined".
const char* to_string(Verdict v);

}  // namespace dyncal::host
