// The commanded TCP path of a run (see commanded_path.hpp).
#include "deflex/evaluate/commanded_path.hpp"

#include <fmt/format.h>

#include "deflex/model/kinematics.hpp"
#include "deflex/text/csv_table.hpp"
#include "deflex/text/errors.hpp"

namespace deflex {

CommandedPath read_commanded_path(const std::string& path, const RobotModel* model) {
  const CsvTable table = CsvTable::read_file(path);
  CommandedPath out;
  if (table.rows() < 2) throw DataError(fmt::format("{}: fewer than two rows: no path", path));
  const bool log = table.has("q_nominal1_deg");
  const bool joints = !log && table.has("q1_deg");
  const bool mm = table.has("x_mm"), m = table.has("x_m");
  std::string time_col = log && table.has("program_t_s") ? "program_t_s" : "t_s";
  table.require({time_col});
  const std::size_t ct = table.column(time_col);
  if (log || joints) {
    if (model == nullptr) {
      throw InputError(fmt::format("{}: a {} gives joints; the TCP path needs the robot (--robot)", path,
                                   log ? "cycle log" : "joint trajectory"));
    }
    out.kind = log ? "cycle log" : "joint trajectory";
    std::vector<std::size_t> cols;
    for (int j = 1; j <= model->dof(); ++j) {
      const std::string name = (log ? "q_nominal" : "q") + std::to_string(j) + "_deg";
      table.require({name});
      cols.push_back(table.column(name));
    }
    Workspace ws(*model);
    JointVector q(model->dof());
    for (std::size_t r = 0; r < table.rows(); ++r) {
      const double t = table.at(r, ct);
      if (!out.trace.empty() && t <= out.trace.back().t_s) {
        if (log && t == out.trace.back().t_s) continue;  // the controller asked twice in one program instant
        table.fail(r, time_col, fmt::format("time {} s is not after the previous row's {} s", t, out.trace.back().t_s));
      }
      for (int j = 0; j < model->dof(); ++j) q[j] = table.at(r, cols[static_cast<std::size_t>(j)]) * kPi / 180.0;
      out.trace.push_back({t, tcp_pose(*model, ws, q).translation()});
    }
    return out;
  }
  if (!mm && !m) {
    throw DataError(
        fmt::format("{}: neither a Cartesian path (t_s,x_mm,y_mm,z_mm or x_m...), a joint trajectory "
                    "(t_s,q1_deg,...) nor a cycle log (program_t_s,q_nominal1_deg,...)",
                    path));
  }
  if (mm && m) {
    throw DataError(fmt::format(
        "{}: columns 'x_mm' and 'x_m': the path is given in two units (which is the command?); keep one", path));
  }
  out.kind = "Cartesian path";
  const std::string s = mm ? "_mm" : "_m";
  table.require({"x" + s, "y" + s, "z" + s});
  const double scale = mm ? 1e-3 : 1.0;
  const std::size_t cx = table.column("x" + s), cy = table.column("y" + s), cz = table.column("z" + s);
  for (std::size_t r = 0; r < table.rows(); ++r) {
    const double t = table.at(r, ct);
    if (!out.trace.empty() && t <= out.trace.back().t_s) {
      table.fail(r, time_col, fmt::format("time {} s is not after the previous row's {} s", t, out.trace.back().t_s));
    }
    out.trace.push_back({t, Vector3(table.at(r, cx), table.at(r, cy), table.at(r, cz)) * scale});
  }
  return out;
}

}  // namespace deflex
