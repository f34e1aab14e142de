// The G-code machine: words given their meaning, modal state, motion blocks into points.
#include "deflex/toolpath/detail/gcode_interpreter.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"

namespace deflex::detail {

namespace {

int gcode_code(const GcodeWord& w) { return static_cast<int>(std::lround(w.value * 10.0)); }

/// Sets `slot` to `w`, or fails when the block already has a word of that group.
template <class Fail>
void gi_put(const GcodeWord*& slot, const GcodeWord& w, const char* group, Fail&& fail) {
  if (slot != nullptr) {
    fail(&w, fmt::format("a second {} in one block", group));
  }
  slot = &w;
}

}  // namespace

GcodeInterpreter::GcodeInterpreter(std::string source, const ToolpathOptions& options)
    : source_(std::move(source)), options_(options) {
  check_toolpath_options(options_);
  summary_.format = ToolpathFormat::kGcode;
  summary_.source = source_;
}

void GcodeInterpreter::fail(const GcodeWord* w, const std::string& what) const {
  if (w == nullptr) {
    fail_text(what);
  }
  fail_word(w->text(line_.text), what);
}

void GcodeInterpreter::fail_word(std::string_view word, const std::string& what) const {
  throw DataError(fmt::format("{}:{}: word '{}': {}", source_, line_.number, word, what));
}

void GcodeInterpreter::fail_text(const std::string& what) const {
  throw DataError(fmt::format("{}:{}: {}", source_, line_.number, what));
}

double GcodeInterpreter::length_scale() const { return units_ == LengthUnit::kInch ? 0.0254 : 1e-3; }

bool GcodeInterpreter::interpret(const SourceLine& line, BlockPoints& points) {
  line_ = line;
  summary_.lines = line.number;
  split_gcode_line(line.text, source_, line.number, words_);
  if (words_.delimiter || (words_.words.empty() && words_.keywords.empty())) {
    return false;
  }
  Block b;
  classify(b);
  apply_settings(b);
  apply_keywords();
  const bool motion = b.g_dwell == nullptr && plan_motion(b, points);
  if (b.m_end != nullptr) {
    end_line_ = line.number;
  }
  return motion;
}

void GcodeInterpreter::classify(Block& b) const {
  const auto failer = [this](const GcodeWord* w, const std::string& what) { fail(w, what); };
  for (const GcodeWord& w : words_.words) {
    if (w.index == 3) {
      if (w.letter < 'A' || w.letter > 'C') {
        fail(&w, "only A3=, B3=, C3= (a tool-axis vector) take an index");
      }
      gi_put(b.vector[w.letter - 'A'], w, "tool-axis vector component of this name", failer);
      continue;
    }
    switch (w.letter) {
      case 'X':
      case 'Y':
      case 'Z':
        gi_put(b.axis[w.letter - 'X'], w, fmt::format("'{}'", w.letter).c_str(), failer);
        break;
      case 'A':
      case 'B':
      case 'C':
        gi_put(b.rotary[w.letter - 'A'], w, fmt::format("'{}'", w.letter).c_str(), failer);
        break;
      case 'I':
      case 'J':
      case 'K':
        gi_put(b.offset[w.letter - 'I'], w, fmt::format("'{}'", w.letter).c_str(), failer);
        break;
      case 'R':
        gi_put(b.r, w, "'R'", failer);
        break;
      case 'F':
        gi_put(b.f, w, "'F'", failer);
        break;
      case 'S':
        gi_put(b.s, w, "'S'", failer);
        break;
      case 'T':
        gi_put(b.t, w, "'T'", failer);
        break;
      case 'P':
        gi_put(b.p, w, "'P'", failer);
        break;
      case 'H':
        gi_put(b.h, w, "'H'", failer);
        break;
      case 'D':
        gi_put(b.d, w, "'D'", failer);
        break;
      case 'N':
      case 'O':
        if (w.value < 0 || w.value != std::floor(w.value)) {
          fail(&w, "a block or program number is a whole number >= 0");
        }
        break;
      case 'G':
        classify_g(w, b);
        break;
      case 'M':
        classify_m(w, b);
        break;
      default:
        fail(&w, fmt::format("'{}' is not a word deflex reads (it reads G, M, X, Y, Z, A, B, C, A3=, B3=, C3=, I, J, "
                             "K, R, F, S, T, H, D, N, O, and P with G4)",
                             w.letter));
    }
  }
  if (b.p != nullptr && b.g_dwell == nullptr) {
    fail(b.p, "P is read only as G4's dwell time");
  }
}

void GcodeInterpreter::classify_g(const GcodeWord& w, Block& b) const {
  const auto failer = [this](const GcodeWord* x, const std::string& what) { fail(x, what); };
  if (std::abs(w.value * 10.0 - std::round(w.value * 10.0)) > 1e-9 || w.value < 0 || w.value > 1000) {
    fail(&w, "not a G code");
  }
  const int c = gcode_code(w);
  const bool siemens = options_.dialect == GcodeDialect::kSiemens;
  if (c == 0 || c == 10 || c == 20 || c == 30 || c == 800) {
    gi_put(b.g_motion, w, "motion G code (G0, G1, G2, G3, G80)", failer);
  } else if (c == 170 || c == 180 || c == 190) {
    gi_put(b.g_plane, w, "plane (G17, G18, G19)", failer);
  } else if (c == 200 || c == 210 || (siemens && (c == 700 || c == 710 || c == 7000 || c == 7100))) {
    gi_put(b.g_units, w, "unit (G20, G21)", failer);
  } else if (c == 900 || c == 910) {
    gi_put(b.g_distance, w, "distance mode (G90, G91)", failer);
  } else if (c == 901 || c == 911) {
    gi_put(b.g_arc_distance, w, "arc centre mode (G90.1, G91.1)", failer);
  } else if (c == 940) {
    gi_put(b.g_feed_mode, w, "feed mode", failer);
  } else if (c == 400) {
    gi_put(b.g_comp, w, "cutter compensation G code", failer);
  } else if (c == 430 || c == 434 || c == 435 || c == 490) {
    gi_put(b.g_length, w, "tool length G code (G43, G43.4, G43.5, G49)", failer);
  } else if (c >= 540 && c <= 590 && c % 10 == 0) {
    gi_put(b.g_offset, w, "work offset (G54-G59)", failer);
  } else if (c == 610 || c == 640) {
    gi_put(b.g_path, w, "path control mode (G61, G64)", failer);
  } else if (c == 40) {
    gi_put(b.g_dwell, w, "G4", failer);
  } else if (c == 930 || c == 950) {
    fail(&w,
         "inverse-time (G93) and per-revolution (G95) feeds are not read: post the program with G94 (feed in "
         "mm/min or in/min)");
  } else if (c == 410 || c == 420) {
    fail(&w,
         "cutter radius compensation (G41, G42) moves the tool off the programmed path by a radius the control "
         "holds: post the program with the cutter's centre path (compensation in the computer)");
  } else if (c == 730 || c == 740 || c == 760 || (c >= 810 && c <= 890)) {
    fail(&w,
         "canned cycles (G73, G74, G76, G81-G89) are not read: post the program with the cycles expanded into "
         "G0/G1 moves");
  } else if (c == 280 || c == 300 || c == 530) {
    fail(&w,
         "moves to the machine's home or in machine coordinates (G28, G30, G53) go to points the program does "
         "not state: replace them by G0 moves to stated points");
  } else if ((c == 700 || c == 710) && !siemens) {
    fail(&w,
         "G70/G71 are inch/mm on a Siemens control and cycles on others: write G20/G21, or read the file with "
         "the Siemens dialect");
  } else {
    fail(&w,
         "a G code deflex does not read (it reads G0-G3, G4, G17-G19, G20, G21, G40, G43, G43.4, G43.5, G49, "
         "G54-G59, G61, G64, G80, G90, G91, G90.1, G91.1, G94)");
  }
}

void GcodeInterpreter::classify_m(const GcodeWord& w, Block& b) const {
  const auto failer = [this](const GcodeWord* x, const std::string& what) { fail(x, what); };
  const double v = w.value;
  if (v != std::floor(v) || v < 0 || v > 1000) {
    fail(&w, "not an M code");
  }
  switch (static_cast<int>(v)) {
    case 0:
    case 1:
      gi_put(b.m_stop, w, "program stop (M0, M1)", failer);
      break;
    case 2:
    case 30:
      gi_put(b.m_end, w, "program end (M2, M30)", failer);
      break;
    case 3:
    case 4:
    case 5:
      gi_put(b.m_spindle, w, "spindle M code (M3, M4, M5)", failer);
      break;
    case 6:
      gi_put(b.m_tool_change, w, "M6", failer);
      break;
    case 7:
    case 8:
    case 9:
      gi_put(b.m_coolant, w, "coolant M code (M7, M8, M9)", failer);
      break;
    default:
      fail(&w, "an M code deflex does not read (it reads M0-M9 and M30)");
  }
}

void GcodeInterpreter::apply_settings(const Block& b) {
  if (b.g_units != nullptr) {
    const int c = gcode_code(*b.g_units);
    const LengthUnit u = (c == 200 || c == 700 || c == 7000) ? LengthUnit::kInch : LengthUnit::kMillimetre;
    if (!first_point_ && u != units_) {
      summary_.units_changed = true;
    }
    units_ = u;
  }
  if (b.f != nullptr) {
    const double mm_per_min = b.f->value * length_scale() * 1e3;
    if (b.f->value < 0 || mm_per_min > toolpath_limits::kMaxFeedMmPerMin) {
      fail(b.f, fmt::format("a feed of {} mm/min is outside 0..{} mm/min", number_text(mm_per_min),
                            number_text(toolpath_limits::kMaxFeedMmPerMin)));
    }
    feed_m_s_ = mm_per_min / 60000.0;
    feed_line_ = line_.number;
  }
  apply_spindle_and_tool(b);
  if (b.g_dwell != nullptr) {
    const GcodeWord* time = b.p != nullptr ? b.p : b.axis[0];
    bool moves = b.axis[1] != nullptr || b.axis[2] != nullptr || b.g_motion != nullptr || b.r != nullptr;
    for (int k = 0; k < 3; ++k) {
      moves = moves || b.rotary[k] != nullptr || b.vector[k] != nullptr || b.offset[k] != nullptr;
    }
    if (time == nullptr || time->value < 0 || (b.p != nullptr && b.axis[0] != nullptr) || moves) {
      fail(b.g_dwell, "G4 (dwell) takes its time in P or X and nothing that moves");
    }
  }
  apply_modes(b);
}

void GcodeInterpreter::apply_spindle_and_tool(const Block& b) {
  if (b.s != nullptr) {
    if (b.s->value < 0 || b.s->value > toolpath_limits::kMaxSpindleRpm) {
      fail(b.s, fmt::format("a spindle speed outside 0..{} rev/min", number_text(toolpath_limits::kMaxSpindleRpm)));
    }
    spindle_rpm_ = b.s->value;
    spindle_rpm_line_ = line_.number;
  }
  for (const GcodeWord* w : {b.h, b.d}) {
    if (w != nullptr && (w->value < 0 || w->value > 9999 || w->value != std::floor(w->value))) {
      fail(w, "a tool offset number is a whole number in 0..9999");
    }
  }
  if (b.t != nullptr) {
    if (b.t->value < 0 || b.t->value > 99999 || b.t->value != std::floor(b.t->value)) {
      fail(b.t, "a tool number is a whole number in 0..99999");
    }
    selected_tool_ = static_cast<int>(b.t->value);
    add_tool(selected_tool_);
  }
  if (b.m_tool_change != nullptr) {
    active_tool_ = selected_tool_;
  }
  if (b.m_spindle != nullptr) {
    const int m = static_cast<int>(b.m_spindle->value);
    spindle_ = m == 3 ? SpindleState::kClockwise : m == 4 ? SpindleState::kCounterClockwise : SpindleState::kOff;
    spindle_off_line_ = m == 5 ? line_.number : 0;
  }
}

void GcodeInterpreter::add_tool(int number) {
  for (const ToolEntry& t : summary_.tools) {
    if (t.number == number) {
      return;
    }
  }
  if (summary_.tools.size() >= toolpath_limits::kMaxTools) {
    fail_text(fmt::format("more than {} different tools", toolpath_limits::kMaxTools));
  }
  summary_.tools.push_back({number, line_.number, std::nullopt});
}

void GcodeInterpreter::apply_modes(const Block& b) {
  if (b.g_plane != nullptr) {
    const int c = gcode_code(*b.g_plane);
    plane_ = c == 170 ? ArcPlane::kXy : c == 180 ? ArcPlane::kZx : ArcPlane::kYz;
  }
  if (b.g_length != nullptr) {
    const int c = gcode_code(*b.g_length);
    tcp_vector_ = c == 435;
  }
  if (b.g_offset != nullptr) {
    const int c = gcode_code(*b.g_offset);
    if (work_offset_ != 0 && c != work_offset_) {
      fail(b.g_offset, fmt::format("the program changes work offset from G{} (line {}): deflex places one "
                                   "workpiece frame, so a program uses one work offset",
                                   work_offset_ / 10, work_offset_line_));
    }
    if (work_offset_ == 0) {
      work_offset_ = c;
      work_offset_line_ = line_.number;
    }
  }
  if (b.g_distance != nullptr) {
    incremental_ = gcode_code(*b.g_distance) == 910;
  }
  if (b.g_arc_distance != nullptr) {
    arc_centre_absolute_ = gcode_code(*b.g_arc_distance) == 901;
  }
  if (b.g_motion != nullptr) {
    const int c = gcode_code(*b.g_motion);
    motion_ = c == 800 ? -1 : c / 10;
  }
}

void GcodeInterpreter::apply_keywords() {
  for (const GcodeKeyword& k : words_.keywords) {
    std::string name;
    for (const char c : k.name) {
      name += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
    if (name == "TRAORI") {
      traori_ = true;
    } else if (name == "TRAFOOF") {
      traori_ = false;
    } else if (name != "ORIWKS" && name != "ORIVECT") {
      throw DataError(
          fmt::format("{}:{}: word '{}': not a word deflex reads (of the keywords it reads TRAORI, "
                      "TRAFOOF, ORIWKS and ORIVECT)",
                      source_, line_.number, k.name));
    }
  }
}

}  // namespace deflex::detail
