#pragma once
// A torque channel's delay against the position channel undone on the log (dyncal diagnose's
// torque_delay; identify, diagnose and predict --torque-delay, identify --effects).

#include "dyncal_host/common/model_effects.hpp"
#include "dyncal_host/logs/joint_log.hpp"

namespace dyncal::host {

/// Undoes `delay` on `log`: joint delay.joint's torque becomes tau_j(t + seconds), linearly
/// interpolated between the log's samples inside each segment (log.segments()); where t + seconds
/// falls beyond a segment's end (its first sample, for a negative delay) the end's value is held, a
/// stretch of |seconds| per segment. Linear interpolation is a low-pass of its own, small in the
/// identification's band: a half-sample shift scales a frequency f by cos(pi f / f_s), 0.8 % down at
/// f_s / 25. Throws InputError on a joint outside the log.
void undo_torque_delay(JointLog& log, const TorqueDelay& delay);

}  // namespace dyncal::host
