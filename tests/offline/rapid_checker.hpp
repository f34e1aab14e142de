// A small, independent well-formedness checker for the RAPID modules deflex writes, used by the
// tests: module and procedure structure, declarations against uses, value ranges. It knows RAPID
// syntax, not the writer's code, so it can catch the writer's mistakes.
#pragma once

#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "deflex/model/robot_model.hpp"

namespace deflex::test {

struct RapidDeclaration {
  std::string storage, type, name, value;
  int line = 0;
};

struct RapidCheck {
  std::vector<std::string> problems;
  std::string module_name;
  std::map<std::string, RapidDeclaration> declarations;
  std::vector<std::string> moved_to;  ///< targets in the order of the move instructions
};

inline std::vector<double> rapid_numbers(const std::string& s) {
  std::vector<double> out;
  static const std::regex number(R"([-+]?[0-9]*\.?[0-9]+(?:[eE][-+]?[0-9]+)?)");
  for (auto it = std::sregex_iterator(s.begin(), s.end(), number); it != std::sregex_iterator(); ++it) {
    out.push_back(std::stod(it->str()));
  }
  return out;
}

/// Checks `text`; joint values of jointtargets against `model`'s limits (degrees).
inline RapidCheck check_rapid_module(const std::string& text, const RobotModel& model) {
  RapidCheck c;
  auto problem = [&](int line, const std::string& what) {
    c.problems.push_back("line " + std::to_string(line) + ": " + what);
  };
  std::vector<std::pair<int, std::string>> lines;  // code without comments, non-empty
  {
    std::istringstream in(text);
    std::string raw;
    int n = 0;
    while (std::getline(in, raw)) {
      ++n;
      const auto bang = raw.find('!');
      std::string code = bang == std::string::npos ? raw : raw.substr(0, bang);
      const auto b = code.find_first_not_of(" \t");
      if (b == std::string::npos) {
        continue;
      }
      code = code.substr(b, code.find_last_not_of(" \t") - b + 1);
      lines.emplace_back(n, code);
    }
  }
  if (lines.empty()) {
    c.problems.push_back("empty module");
    return c;
  }
  static const std::regex module_re(R"(^MODULE\s+([A-Za-z][A-Za-z0-9_]{0,31})(\s*\([A-Z, ]*\))?$)");
  static const std::regex proc_re(R"(^PROC\s+([A-Za-z][A-Za-z0-9_]{0,31})\s*\(\s*\)$)");
  static const std::regex decl_re(
      R"(^(CONST|PERS|VAR)\s+(jointtarget|robtarget|speeddata|zonedata|tooldata|wobjdata|num)\s+([A-Za-z][A-Za-z0-9_]{0,31})\s*:=\s*(.+);$)");
  static const std::regex move_re(
      R"(^(MoveAbsJ|MoveL|MoveJ)\s+([A-Za-z][A-Za-z0-9_]*)(\\NoEOffs)?\s*,\s*([A-Za-z][A-Za-z0-9_]*)\s*,\s*([A-Za-z][A-Za-z0-9_]*)\s*,\s*([A-Za-z][A-Za-z0-9_]*)(\\WObj:=([A-Za-z][A-Za-z0-9_]*))?;$)");
  static const std::regex zone_re(R"(^(fine|z[0-9]+)$)");
  std::smatch m;
  if (!std::regex_match(lines.front().second, m, module_re)) {
    problem(lines.front().first, "first statement is not MODULE name");
  } else {
    c.module_name = m[1];
  }
  if (lines.back().second != "ENDMODULE") {
    problem(lines.back().first, "last statement is not ENDMODULE");
  }
  bool in_proc = false;
  int procs = 0;
  bool has_main = false;
  std::set<std::string> used;
  for (std::size_t i = 1; i + 1 < lines.size(); ++i) {
    const auto& [n, code] = lines[i];
    if (code == "MODULE" || code.rfind("MODULE ", 0) == 0 || code == "ENDMODULE") {
      problem(n, "nested or repeated MODULE/ENDMODULE");
    } else if (std::regex_match(code, m, proc_re)) {
      if (in_proc) {
        problem(n, "PROC inside a PROC");
      }
      in_proc = true;
      ++procs;
      has_main = has_main || m[1] == "main";
    } else if (code == "ENDPROC") {
      if (!in_proc) {
        problem(n, "ENDPROC without PROC");
      }
      in_proc = false;
    } else if (std::regex_match(code, m, decl_re)) {
      if (in_proc) {
        problem(n, "declaration inside a routine");
      }
      RapidDeclaration d{m[1], m[2], m[3], m[4], n};
      if (c.declarations.count(d.name) != 0) {
        problem(n, "'" + d.name + "' declared twice");
      }
      int depth = 0;
      for (char ch : d.value) {
        depth += ch == '[' ? 1 : ch == ']' ? -1 : 0;
        if (depth < 0) {
          break;
        }
      }
      if (depth != 0) {
        problem(n, "unbalanced brackets in '" + d.name + "'");
      }
      const auto v = rapid_numbers(d.value);
      if (d.type == "jointtarget") {
        if (v.size() != 12) {
          problem(n, "jointtarget needs 6 robot and 6 external axes");
        } else {
          for (int j = 0; j < 6; ++j) {
            const double lo = rad_to_deg(model.lower_limits()[j]), hi = rad_to_deg(model.upper_limits()[j]);
            if (v[static_cast<std::size_t>(j)] < lo || v[static_cast<std::size_t>(j)] > hi) {
              problem(n, "joint " + std::to_string(j + 1) + " of '" + d.name + "' outside its limits");
            }
          }
          for (std::size_t j = 6; j < 12; ++j) {
            if (v[j] != 9e9) {
              problem(n, "unused external axis not 9E+09");
            }
          }
        }
      } else if (d.type == "robtarget") {
        if (v.size() != 17) {
          problem(n, "robtarget needs trans(3), rot(4), robconf(4), extax(6)");
        } else {
          for (std::size_t j = 0; j < 3; ++j) {
            if (std::abs(v[j]) > 5000.0) {
              problem(n, "position of '" + d.name + "' beyond 5 m");
            }
          }
          const double qn = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
          if (std::abs(qn - 1.0) > 1e-6) {
            problem(n, "quaternion of '" + d.name + "' not normalised");
          }
          for (std::size_t j = 7; j < 11; ++j) {
            if (v[j] != std::floor(v[j])) {
              problem(n, "confdata of '" + d.name + "' not integer");
            }
          }
          if (v[10] < 0 || v[10] > 7) {
            problem(n, "cfx of '" + d.name + "' outside 0..7");
          }
        }
      } else if (d.type == "speeddata") {
        if (v.size() != 4 || v[0] <= 0 || v[1] <= 0 || v[2] <= 0 || v[3] <= 0) {
          problem(n, "speeddata needs 4 positive values");
        }
      }
      c.declarations[d.name] = d;
    } else if (std::regex_match(code, m, move_re)) {
      if (!in_proc) {
        problem(n, "move instruction outside a routine");
      }
      const std::string instr = m[1], target = m[2], speed = m[4], zone = m[5], tool = m[6];
      used.insert(target);
      used.insert(speed);
      c.moved_to.push_back(target);
      const auto it = c.declarations.find(target);
      if (it != c.declarations.end() && (instr == "MoveAbsJ") != (it->second.type == "jointtarget")) {
        problem(n, instr + " to a " + it->second.type);
      }
      if (!std::regex_match(zone, zone_re)) {
        problem(n, "zone '" + zone + "' is not fine or a predefined zXX");
      }
      if (tool != "tool0" && c.declarations.count(tool) == 0) {
        problem(n, "tool '" + tool + "' neither tool0 nor declared");
      }
    } else if (code == "ConfL\\On;" || code == "ConfJ\\On;") {
      if (!in_proc) {
        problem(n, "instruction outside a routine");
      }
    } else {
      problem(n, "unrecognised statement: " + code);
    }
  }
  if (in_proc) {
    problem(lines.back().first, "PROC without ENDPROC");
  }
  if (procs == 0 || !has_main) {
    c.problems.push_back("no PROC main()");
  }
  for (const auto& [name, d] : c.declarations) {
    if (used.count(name) == 0) {
      problem(d.line, "'" + name + "' declared but never used");
    }
  }
  for (const std::string& name : used) {
    if (c.declarations.count(name) == 0) {
      c.problems.push_back("'" + name + "' used but not declared");
    }
  }
  return c;
}

}  // namespace deflex::test
