#pragma once
// A parameter set in the form a drive's parameter table holds: the compiled model's values (its
// friction and rotor inertia per joint, as the drive's generated feed-forward applies them) and
// effect terms (lib/ effect_terms.hpp). A coupled motor's friction and rotor inertia, which identify
// fits per motor (robot.json's transmission), become a coupling term.

#include <string>
#include <vector>

#include "dyncal/effect_terms.hpp"
#include "dyncal/parameter_table.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/model/parameter_set.hpp"

namespace dyncal::host {

struct DriveTableContent {
  std::vector<double> values;       ///< the compiled model's parameters, in its order
  std::vector<EffectTerm> effects;  ///< coupled motors' terms first, then the set's own effect terms
  std::vector<std::string> notes;   ///< what was converted
};

/// The table form of `params` for `robot`. Each motor m of the params' motor-velocity map (T =
/// motor_velocity_map: robot.json's transmission N as diag(N)^-1 N with friction per motor, the
/// model's coupled motors) that turns with one other joint j (r = T(m, j)) gives a coupling
/// term on joints m and j with ratio r and coefficients (Fc_m, Fv_m, Ia_m) — Ia_m 0 when the model
/// has no separate Ia_m — and those values are set to 0 among the compiled ones: the drive then
/// applies f = Fc sgn(v) + Fv v + Ia a at v = qd_m + r qd_j on joint m and r f on joint j, what
/// identify fitted (T^T times the motor's torque). Throws InputError: params of another robot, a
/// motor turning with more than one other joint (a table term couples two), Eq. 8's power friction
/// of a coupled motor (no table term), more effect terms than kTableMaxEffects.
/// A Coulomb, viscous or rotor-inertia value below 0 by no more than kZ95 times its std is set to 0
/// with a note: the data do not tell it from 0, and a drive takes none below 0.
DriveTableContent drive_table_content(const ParameterSet& params, const RobotDescription& robot);

/// The parameter table of `params` for `robot` as a drive takes it (drive_table_content, float
/// values, the id of the robot the parameters were identified for: a drive of another robot refuses
/// it); the conversion's notes appended to *notes. A Coulomb, viscous or rotor-inertia parameter
/// below 0 within its 95 % interval (kZ95 times its std; 0 as far as the data say) is held at 0 with
/// a note (drive_table_content). Throws InputError as drive_table_content, for such a parameter
/// below 0 beyond its interval or without a std (what a drive refuses, named here with its value; a
/// coupled motor's too), and for more values than a table holds or a value or effect coefficient
/// that is no finite float.
ParameterTable parameter_table(const ParameterSet& params, const RobotDescription& robot,
                               std::vector<std::string>* notes);

}  // namespace dyncal::host
