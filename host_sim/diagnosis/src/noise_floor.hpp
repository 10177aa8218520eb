#pragma once
// The residual a model that lacks nothing would leave (private to host_sim/diagnosis): the log's
// broadband noise after the identification's low-pass, the floor against which the diagnosis says
// how much of a joint's excess residual an effect removed and how much is left.

#include <Eigen/Core>
#include <utility>
#include <vector>

#include "dyncal_host/model/identify_options.hpp"
#include "dyncal_host/model/stacked_data.hpp"

namespace dyncal::host::detail {

/// Per joint, the mean square [Nm^2] per fitted row that broadband noise alone leaves in the
/// residual (S N stacked, rows s N + j) of the stacked data d (filtered at io's cut-off and order
/// at the raw rate raw_rate_hz, decimated to d.rate_hz). From the residual's own high-frequency
/// content: the differences of consecutive kept samples inside each segment (`segments`), where
/// the model's low-frequency errors (the excitation's band) leave next to nothing and filtered white
/// noise leaves 2 (rho(0) - rho(D)) sigma^2, rho the autocorrelation of the zero-phase filter's
/// impulse response at the raw rate, D the decimation; the floor is rho(0) sigma^2. Robustly: the
/// median of the squared differences over the chi-square(1) median 0.4549. It holds every
/// broadband source (the torque's noise, the encoder's through the model's derivatives); a
/// narrowband error inside the filter's band counts as structure.
Eigen::VectorXd noise_floor_per_row(const StackedData& d, const Eigen::VectorXd& residual,
                                    const std::vector<std::pair<Eigen::Index, Eigen::Index>>& segments,
                                    const IdentifyOptions& io, double raw_rate_hz);

}  // namespace dyncal::host::detail
