// `import dyncal`: the library from Python (docs/python.md). Robots and their generated regressors
// as numpy arrays, and the CLI's commands (identify, predict, diagnose, payload) run in-process with
// the CLI's own code: a command returns the document its --report writes, as Python objects with
// every JSON array of numbers as a numpy array, plus the printed report. Errors raise
// dyncal.InputError with the CLI's one-line message.
#include <pybind11/eigen.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <string>
#include <vector>

#include "../host_sim/app/commands.hpp"
#include "../host_sim/app/report_outputs.hpp"
#include "dyncal_host/common/input_error.hpp"
#include "dyncal_host/common/interrupt.hpp"
#include "dyncal_host/common/progress.hpp"
#include "dyncal_host/common/robot_description.hpp"
#include "dyncal_host/identification/pipeline/compiled_robot.hpp"

namespace py = pybind11;

namespace {

using dyncal::host::InputError;

/// A robot folder and its compiled model.
struct Robot {
  dyncal::host::RobotDescription description;
  const dyncal::host::CompiledRobot* model = nullptr;
  std::string robots_dir;
};

Robot load(const std::string& name, const std::string& robots_dir) {
  Robot r;
  r.robots_dir = robots_dir.empty() ? dyncal::host::default_robots_dir() : robots_dir;
  r.description = dyncal::host::load_checked_robot(r.robots_dir, name);  // the CLI's one check
  r.model = &dyncal::host::compiled_robot_for(r.description);
  return r;
}

std::vector<std::string> base_parameter_names(const Robot& r) {
  for (const auto& m : r.model->models)
    if (m.num_base > 0) return {m.names.begin(), m.names.begin() + m.num_base};
  return {};
}

/// Rows of a (S x N) or (N) array as an S x N matrix; `what` names the argument in errors.
Eigen::MatrixXd rows_of(const py::array_t<double, py::array::c_style | py::array::forcecast>& a, int n,
                        const char* what, bool& single) {
  single = a.ndim() == 1;
  if (a.ndim() < 1 || a.ndim() > 2 || a.shape(a.ndim() - 1) != n)
    throw InputError(std::string(what) + ": expected shape (" + std::to_string(n) + ",) or (S, " + std::to_string(n) +
                     "), one column per joint");
  const Eigen::Index s = a.ndim() == 1 ? 1 : a.shape(0);
  Eigen::MatrixXd m(s, n);
  const double* p = a.data();
  for (Eigen::Index i = 0; i < s; ++i)
    for (int j = 0; j < n; ++j) {
      m(i, j) = p[i * n + j];
      if (!std::isfinite(m(i, j)))
        throw InputError(std::string(what) + "[" + std::to_string(i) + ", " + std::to_string(j) + "] is not finite");
    }
  return m;
}

/// Y_b(q, qd, qdd): (N, P) for one sample, (S, N, P) for S samples.
py::array_t<double> regressor(const Robot& r, const py::array_t<double, py::array::c_style | py::array::forcecast>& q,
                              const py::array_t<double, py::array::c_style | py::array::forcecast>& qd,
                              const py::array_t<double, py::array::c_style | py::array::forcecast>& qdd) {
  const int n = r.description.num_joints, p = r.model->num_base;
  bool s1 = false, s2 = false, s3 = false;
  const Eigen::MatrixXd Q = rows_of(q, n, "q", s1), QD = rows_of(qd, n, "qd", s2), QDD = rows_of(qdd, n, "qdd", s3);
  if (Q.rows() != QD.rows() || Q.rows() != QDD.rows() || s1 != s2 || s1 != s3)
    throw InputError("q, qd, qdd: the same shape is needed");
  const Eigen::Index s = Q.rows();
  py::array_t<double> out(s1 ? std::vector<py::ssize_t>{n, p} : std::vector<py::ssize_t>{s, n, p});
  double* o = out.mutable_data();
  for (Eigen::Index i = 0; i < s; ++i) {
    const Eigen::MatrixXd Y =
        r.model->base_regressor(Q.row(i).transpose(), QD.row(i).transpose(), QDD.row(i).transpose());
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < p; ++k) o[(i * n + j) * p + k] = Y(j, k);
  }
  return out;
}

/// A JSON value as Python: objects as dicts, arrays of numbers (of any depth, rectangular) as numpy.
py::object to_python(const nlohmann::json& j);

bool numeric_array(const nlohmann::json& j, std::vector<py::ssize_t>& shape, std::size_t depth = 0) {
  if (!j.is_array() || j.empty()) return false;
  if (depth == shape.size()) shape.push_back(static_cast<py::ssize_t>(j.size()));
  if (shape[depth] != static_cast<py::ssize_t>(j.size())) return false;
  for (const auto& x : j) {
    if (x.is_number()) {
      if (depth + 1 != shape.size()) return false;
    } else if (!numeric_array(x, shape, depth + 1)) {
      return false;
    }
  }
  return true;
}

void flatten(const nlohmann::json& j, std::vector<double>& out) {
  if (j.is_number()) {
    out.push_back(j.get<double>());
    return;
  }
  for (const auto& x : j) flatten(x, out);
}

py::object to_python(const nlohmann::json& j) {
  std::vector<py::ssize_t> shape;
  if (numeric_array(j, shape)) {
    std::vector<double> flat;
    flatten(j, flat);
    py::array_t<double> a(shape);
    std::copy(flat.begin(), flat.end(), a.mutable_data());
    return std::move(a);
  }
  if (j.is_object()) {
    py::dict d;
    for (const auto& [k, v] : j.items()) d[py::str(k)] = to_python(v);
    return std::move(d);
  }
  if (j.is_array()) {
    py::list l;
    for (const auto& x : j) l.append(to_python(x));
    return std::move(l);
  }
  if (j.is_boolean()) return py::bool_(j.get<bool>());
  if (j.is_number_integer()) return py::int_(j.get<long long>());
  if (j.is_number()) return py::float_(j.get<double>());
  if (j.is_string()) return py::str(j.get<std::string>());
  return py::none();
}

/// keyword arguments as command-line options: a_b=v is --a-b v; True a flag, False left out; a
/// list repeats the option (--data A --data B).
std::vector<std::string> options_of(const py::kwargs& kwargs) {
  std::vector<std::string> args;
  for (const auto& [key, value] : kwargs) {
    std::string name = "--" + py::str(key).cast<std::string>();
    for (auto& c : name)
      if (c == '_') c = '-';
    if (name == "--report") throw InputError("report: the command's report is what it returns");
    const auto add = [&](const py::handle& v) {
      if (py::isinstance<py::bool_>(v)) {
        if (v.cast<bool>()) args.push_back(name);
        return;
      }
      args.push_back(name);
      args.push_back(py::str(v).cast<std::string>());
    };
    if (py::isinstance<py::list>(value) || py::isinstance<py::tuple>(value)) {
      for (const auto& v : value) add(v);
    } else {
      add(value);
    }
  }
  return args;
}

/// Runs `dyncal COMMAND OPTIONS --report TMP` in-process: the report document and the printed text.
py::dict run_command(const std::string& command, const py::kwargs& kwargs) {
  const auto report = std::filesystem::temp_directory_path() /
                      ("dyncal_python_" + std::to_string(::getpid()) + "_" + command + ".json");
  std::vector<std::string> args{"dyncal", command};
  for (auto& a : options_of(kwargs)) args.push_back(std::move(a));
  {  // the report's command_line: the equivalent dyncal command (without the module's own --report)
    std::vector<char*> line;
    for (auto& a : args) line.push_back(a.data());
    dyncal::app::set_command_line(static_cast<int>(line.size()), line.data());
  }
  args.push_back("--report");
  args.push_back(report.string());
  CLI::App app{"dyncal"};
  app.require_subcommand(1);
  dyncal::app::Action run;
  dyncal::app::add_commands(app, run);
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  try {
    app.parse(static_cast<int>(argv.size()), const_cast<char**>(argv.data()));
  } catch (const CLI::CallForHelp&) {  // help=True: the command's help text, as `dyncal COMMAND --help` prints it
    py::dict out;
    out["help"] = app.get_subcommand(command)->help();
    return out;
  } catch (const CLI::ParseError& e) {
    throw InputError(e.what());
  }
  std::ostringstream text;
  std::streambuf* saved = std::cout.rdbuf(text.rdbuf());
  int code = 0;
  try {
    code = run ? run() : 0;
  } catch (...) {
    std::cout.rdbuf(saved);
    std::filesystem::remove(report);
    throw;
  }
  std::cout.rdbuf(saved);
  // Exit 1 with a report: a gate (gate=, require=) failed; the report says which items (docs/gates.md).
  if (code != 0 && !(code == 1 && std::filesystem::exists(report)))
    throw InputError("dyncal " + command + " exited with " + std::to_string(code));
  std::ifstream in(report);
  nlohmann::json doc = nlohmann::json::parse(in);
  std::filesystem::remove(report);
  if (code != 0 && !(doc.contains("gate") && !doc["gate"].value("passed", true)))
    throw InputError("dyncal " + command + " exited with " + std::to_string(code));
  py::dict out = to_python(doc).cast<py::dict>();
  out["report_text"] = text.str();
  return out;
}

}  // namespace

PYBIND11_MODULE(dyncal, m) {
  m.doc() = "dyncal: dynamic calibration of serial robot arms (docs/python.md)";
  static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const dyncal::host::Interrupted& e) {  // the drive was stopped first (stream_run)
      PyErr_SetString(PyExc_KeyboardInterrupt, e.what());
    } catch (const InputError& e) {
      PyErr_SetString(input_error.ptr(), e.what());
    }
  });

  py::class_<Robot>(m, "Robot",
                    "A robot folder (robots/<name>/robot.json) and its compiled model. Robot(name, robots_dir='') "
                    "raises InputError for an unknown or malformed robot, or one this build did not compile.")
      .def(py::init(&load), py::arg("name"), py::arg("robots_dir") = "")
      .def_property_readonly("name", [](const Robot& r) { return r.description.name; })
      .def_property_readonly("joints", [](const Robot& r) { return r.description.num_joints; })
      .def_property_readonly("joint_names", [](const Robot& r) { return r.description.joint_names; })
      .def_property_readonly("base_parameter_names", &base_parameter_names,
                             "names of the base parameters (Gautier), the columns of regressor()")
      .def_property_readonly("q_min", [](const Robot& r) { return r.description.q_min; })
      .def_property_readonly("q_max", [](const Robot& r) { return r.description.q_max; })
      .def_property_readonly("qd_max", [](const Robot& r) { return r.description.qd_max; })
      .def_property_readonly("tau_max", [](const Robot& r) { return r.description.tau_max; })
      .def("regressor", &regressor, py::arg("q"), py::arg("qd"), py::arg("qdd"),
           "The generated base regressor Y_b(q, qd, qdd) [rad, rad/s, rad/s^2]: tau = Y_b phi_b [Nm]. Arrays of "
           "shape (N,) give (N, P); (S, N) give (S, N, P), P = len(base_parameter_names).")
      .def_property_readonly(
          "nominal_standard",
          [](const Robot& r) {
            return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(
                r.model->nominal_standard.data(), static_cast<Eigen::Index>(r.model->nominal_standard.size())));
          },
          "the standard parameters of robot.json's inertials (10 per link: m, m c [3], I about the joint frame [6])")
      .def(
          "standard_to_base",
          [](const Robot& r, const Eigen::VectorXd& phi) {
            if (phi.size() != r.model->num_standard)
              throw InputError("phi: " + std::to_string(phi.size()) + " values, the robot has " +
                               std::to_string(r.model->num_standard) + " standard parameters");
            return r.model->standard_to_base(phi);
          },
          py::arg("phi"), "The base parameters (Gautier) of the standard parameters phi.")
      .def(
          "inverse_dynamics",
          [](const Robot& r, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
             const Eigen::VectorXd& phi) {
            const int n = r.description.num_joints;
            if (q.size() != n || qd.size() != n || qdd.size() != n || phi.size() != r.model->num_standard)
              throw InputError("inverse_dynamics: q, qd, qdd of " + std::to_string(n) + " values and phi of " +
                               std::to_string(r.model->num_standard));
            return r.model->inverse_dynamics(q, qd, qdd, phi);
          },
          py::arg("q"), py::arg("qd"), py::arg("qdd"), py::arg("phi"),
          "tau [Nm] = ID(q, qd, qdd; phi) of one sample, the generated Newton-Euler (not the regressor).")
      .def("__repr__", [](const Robot& r) {
        return "<dyncal.Robot " + r.description.name + ", " + std::to_string(r.description.num_joints) + " joints>";
      });

  m.def(
      "set_progress",
      [](py::object callback) {
        if (callback.is_none()) {
          dyncal::host::set_progress_sink({});
          return;
        }
        dyncal::host::set_progress_sink([callback](const dyncal::host::ProgressUpdate& u) {
          py::gil_scoped_acquire gil;
          callback(u.task, u.done, u.total, u.finished);
        });
      },
      py::arg("callback"),
      "Progress of the long commands (diagnose, identify's folds): callback(task, done, total, finished) is "
      "called as they go, at most once per 1 % of a task; None (the default) keeps them quiet.");
  // The callback must not outlive the interpreter.
  py::module_::import("atexit").attr("register")(py::cpp_function([] { dyncal::host::set_progress_sink({}); }));

  for (const char* command : {"identify", "predict", "diagnose", "payload"}) {
    const std::string name = command;
    m.def(
        command, [name](const py::kwargs& kwargs) { return run_command(name, kwargs); },
        ("`dyncal " + name +
         "` with its command-line options as keyword arguments (data='log.csv', model='eq7', validate_last=0.3, "
         "drop_outliers=True; a list repeats an option). Returns the document --report writes, as a dict, with "
         "every array of numbers as a numpy array, and 'report_text': what the command prints. Raises InputError "
         "with the CLI's one-line message; a failed gate (gate='station.yaml', require=['key=value']) returns the "
         "report, "
         "its 'gate' saying which items failed.")
            .c_str());
  }
}
