#include "dyncal_host/identification/methods/effect_model.hpp"

#include <algorithm>
#include <cmath>

#include "dyncal/effect_terms.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/robot_description.hpp"

namespace dyncal::host {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;

Index effect_column_count(const std::vector<ModelEffect>& effects) {
  Index m = 0;
  for (const ModelEffect& e : effects) m += static_cast<Index>(effect_param_names(e).size());
  return m;
}

bool effect_column_steps(EffectKind kind, int column) {
  switch (kind) {
    case EffectKind::stribeck:
    case EffectKind::velocity_power:
    case EffectKind::load_friction:
      return true;
    case EffectKind::asymmetric_friction:
    case EffectKind::coupling:
      return column == 0;  // [qd > 0], sgn(v); qd [qd > 0], v and a are continuous
    default:
      return false;
  }
}

std::vector<bool> effect_columns_with_sign(const std::vector<ModelEffect>& effects) {
  std::vector<bool> out;
  for (const ModelEffect& e : effects) {
    const int width = static_cast<int>(effect_param_names(e).size());
    for (int c = 0; c < width; ++c) out.push_back(effect_column_steps(e.kind, c));
  }
  return out;
}

MatrixXd effect_columns_over_time(const std::vector<ModelEffect>& effects, const MatrixXd& q, const MatrixXd& qd,
                                  const MatrixXd& qdd, const MatrixXd& v_raw, const VectorXd& band) {
  const Index S = q.rows(), N = q.cols(), m = effect_column_count(effects);
  MatrixXd out = MatrixXd::Zero(S, N * m);
  const auto velocity = signed_velocity;
  double c[3];
  Index col = 0;
  for (const ModelEffect& e : effects) {
    const Index width = static_cast<Index>(effect_param_names(e).size());
    if (e.kind != EffectKind::load_friction) {
      const int i = e.joint, k = e.kind == EffectKind::coupling ? e.joint2 : e.joint;
      // A coupling's signed ratio r (lib/ effect_terms.hpp); 1 for the per-joint kinds.
      const double sign = e.kind == EffectKind::coupling ? e.sign * (e.shape > 0 ? e.shape : 1.0) : 1.0;
      for (Index s = 0; s < S; ++s) {
        double v, a;
        if (e.kind == EffectKind::coupling) {
          v = velocity(qd(s, i) + sign * qd(s, k), v_raw(s, i) + sign * v_raw(s, k),
                       std::hypot(band[i], sign * band[k]));
          a = qdd(s, i) + sign * qdd(s, k);
        } else {
          v = velocity(qd(s, i), v_raw(s, i), band[i]);
          a = qdd(s, i);
        }
        // The motor's v and a passed whole (second joint 0): effect_columns adds sign qd2.
        const int w = effect_columns(e.kind, e.shape, sign, q(s, i), v, a, 0.0, 0.0, 0.0, c);
        for (int x = 0; x < w; ++x) {
          out(s, i * m + col + x) = c[x];
          if (e.kind == EffectKind::coupling) out(s, k * m + col + x) = sign * c[x];
        }
      }
    }
    col += width;
  }
  return out;
}

MatrixXd effect_design(const StackedData& d, const std::vector<ModelEffect>& effects, const VectorXd& tau_rb) {
  const int N = static_cast<int>(d.q.cols());
  const Index S = d.t.size();
  if (d.E.cols() != effect_column_count(effects) || d.E.rows() != S * N)
    throw InputError("internal: the data were not prepared with these effect terms");
  MatrixXd E = d.E;
  Index col = 0;
  for (const ModelEffect& e : effects) {
    if (e.kind == EffectKind::load_friction) {
      const int i = e.joint;
      for (Index s = 0; s < S; ++s) {
        const double v = d.qd(s, i);
        E(s * N + i, col) = std::abs(tau_rb[s * N + i]) * (v > 0 ? 1.0 : (v < 0 ? -1.0 : 0.0));
      }
    }
    col += static_cast<Index>(effect_param_names(e).size());
  }
  return E;
}

void set_effect_columns(StackedData& d, Index declared, const std::vector<ModelEffect>& effects,
                        const std::vector<bool>& use, const VectorXd& tau_rb) {
  const MatrixXd E = effect_design(d, effects, tau_rb);
  const int N = static_cast<int>(d.q.cols());
  Index used = 0;
  for (const bool u : use) used += u ? 1 : 0;
  d.W.conservativeResize(Eigen::NoChange, declared + used);
  d.names.resize(static_cast<size_t>(declared));
  Index col = 0, out = declared;
  for (const ModelEffect& e : effects) {
    for (const std::string& name : effect_param_names(e)) {
      if (use[static_cast<size_t>(col)]) {
        d.W.col(out++) = E.col(col);
        d.names.push_back(name);
      }
      ++col;
    }
  }
  d.W_load.resize(0, 0);
  d.regressor_rows = [N](const StackedData& data, Index s, bool load, MatrixXd& K) {
    if (load) throw InputError("internal: a model with effect terms has no load regressor");
    K = data.W.middleRows(s * N, N);
  };
}

TermSetModel with_effect_parameters(const TermSetModel& model, const std::vector<ModelEffect>& effects,
                                    const std::vector<bool>& use) {
  TermSetModel out = model;
  size_t col = 0;
  for (const ModelEffect& e : effects) {
    for (const std::string& name : effect_param_names(e)) {
      if (use[col++]) {
        out.names.push_back(name);
        out.info.push_back(dyncal::ParamInfo{dyncal::ParamKind::term, -1, 0u, e.joint + 1});
        ++out.num_params;
      }
    }
  }
  out.regressor = nullptr;  // the effects' columns are not the compiled regressor's: rows come from StackedData::W
  return out;
}

VectorXd effect_parameter_scales(const StackedData& d, Index declared, const TermSetModel& model,
                                 const RobotDescription& robot) {
  const Index N = d.q.cols(), S = d.t.size();
  VectorXd out(model.num_params - declared);
  for (Index i = declared; i < model.num_params; ++i) {
    const int j = model.info[static_cast<size_t>(i)].joint - 1;
    double largest = 0;
    for (Index s = 0; s < S; ++s) largest = std::max(largest, std::abs(d.W(s * N + j, i)));
    const double tau = robot.tau_max[j];
    out[i - declared] = largest > 0 ? tau / largest : tau;
  }
  return out;
}

std::vector<bool> effect_columns_without_load_friction(const std::vector<ModelEffect>& effects) {
  std::vector<bool> out;
  for (const ModelEffect& e : effects)
    for (size_t c = 0; c < effect_param_names(e).size(); ++c) out.push_back(e.kind != EffectKind::load_friction);
  return out;
}

VectorXd rigid_body_torque(const StackedData& d, const VectorXd& phi) {
  return d.W.leftCols(d.num_base) * phi.head(d.num_base);
}

MatrixXd model_design(const StackedData& d, const std::vector<ModelEffect>& effects, const VectorXd& phi) {
  const MatrixXd E = effect_design(d, effects, rigid_body_torque(d, phi));
  MatrixXd X(d.W.rows(), d.W.cols() + E.cols());
  X << d.W, E;
  return X;
}

}  // namespace dyncal::host
