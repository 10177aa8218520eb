// MuJoCo's compilation and inverse dynamics of an MJCF file (mujoco_model.hpp).
#include "mujoco_model.hpp"

#include <mujoco/mujoco.h>

#include "dyncal_host/common/input_error.hpp"

namespace dyncal::app {

MujocoModel::MujocoModel(const std::string& path) {
  char error[1000] = "";
  model_ = mj_loadXML(path.c_str(), nullptr, error, sizeof error);
  if (model_ == nullptr) throw host::InputError(path + ": MuJoCo does not compile it: " + error);
  model_->opt.disableflags |= mjDSBL_CONSTRAINT;
  data_ = mj_makeData(model_);
}

MujocoModel::~MujocoModel() {
  if (data_ != nullptr) mj_deleteData(data_);
  if (model_ != nullptr) mj_deleteModel(model_);
}

int MujocoModel::dofs() const {
  return model_->nv;
}

std::string MujocoModel::joint_name(int i) const {
  const char* name = mj_id2name(model_, mjOBJ_JOINT, i);
  return name == nullptr ? std::string() : std::string(name);
}

Eigen::VectorXd MujocoModel::inverse_dynamics(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                              const Eigen::VectorXd& qdd) {
  const int n = model_->nv;
  for (int i = 0; i < n; ++i) {
    data_->qpos[i] = q[i];
    data_->qvel[i] = qd[i];
    data_->qacc[i] = qdd[i];
  }
  mj_inverse(model_, data_);
  return Eigen::Map<const Eigen::VectorXd>(data_->qfrc_inverse, n);
}

}  // namespace dyncal::app
