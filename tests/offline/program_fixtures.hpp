// What the program-reader tests share: a load, reachable targets, a module and a data list around
// them, and the calls that compensate them from text.
#pragma once

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "deflex/force/constant_wrench_model.hpp"
#include "deflex/offline/detail/krl_program.hpp"
#include "deflex/offline/detail/rapid_program.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "support/error_of.hpp"

namespace deflex::program_fixtures {

inline const ConstantWrenchModel kPush(Wrench((Wrench() << 0, 0, -300, 0, 0, 0).finished()));

// Reachable IRB 6700 targets (made with deflex ik): tool0 pointing down 1.6 m ahead.
inline const char* const kP1 = "[[1600,0,1200],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]";
inline const char* const kP2 = "[[1600,200,1200],[0,0,1,0],[0,0,0,0],[9E+09,9E+09,9E+09,9E+09,9E+09,9E+09]]";

inline std::string module(const std::string& data, const std::string& body) {
  return "MODULE T\n" + data + "  PROC main()\n" + body + "  ENDPROC\nENDMODULE\n";
}

inline ProgramCompensation rapid(const std::string& text, const ProgramOptions& options = {},
                                 const ForceModel& force = kPush) {
  return compensate_rapid_module(builtin_irb6700(), force, "t.mod", text, "out.mod", options);
}

/// The error compensating `text` gives must hold every fragment.
inline void expect_error(const std::string& text, const std::vector<std::string>& fragments,
                         const ProgramOptions& options = {}) {
  const std::string msg = test::error_of([&] { (void)rapid(text, options); });
  for (const auto& f : fragments) {
    EXPECT_NE(msg.find(f), std::string::npos) << "'" << msg << "' lacks '" << f << "'";
  }
}

inline ProgramCompensation krl(const std::string& src, const std::string& dat, const ProgramOptions& options) {
  return compensate_krl_program(
      load_robot(std::string(DEFLEX_SOURCE_DIR) + "/examples/robots/kuka_kr210_r3100_2_flange.yaml"), kPush, "p.src",
      src, "p.dat", dat, "out.src", options);
}

inline const char* const kDat =
    "DEFDAT dxt\n"
    "DECL E6POS XP1={X 1800.0,Y -300.0,Z 600.0,A 20.0,B 75.0,C 15.0,S 2,T 10,E1 0.0}\n"
    "DECL FDAT FP1={TOOL_NO 1,BASE_NO 0,IPO_FRAME #BASE,POINT2[] \" \",TQ_STATE FALSE}\n"
    "DECL FRAME TSPINDLE={X 250,Y 0,Z 0,A 0,B 0,C 0}\n"
    "DECL E6POS P[2]\n"
    "P[1]={X 1800.0,Y -200.0,Z 600.0,A 20.0,B 75.0,C 15.0,S 2,T 10}\n"
    "ENDDAT\n";

}  // namespace deflex::program_fixtures
