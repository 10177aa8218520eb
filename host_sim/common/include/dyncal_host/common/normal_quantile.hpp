#pragma once
// The one 95 % quantile every interval and verdict of the host uses.

namespace dyncal::host {

/// The two-sided 95 % quantile of the standard normal distribution: a 95 % interval is value +- kZ95
/// std (identify's verdicts, the pages' intervals, the gates' physics bound, a drive table's zero).
inline constexpr double kZ95 = 1.959963984540054;

}  // namespace dyncal::host
