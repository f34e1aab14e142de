// The compensated G-code program, written while the source is read again line by line.
#include "deflex/toolpath/gcode_write_back.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <vector>

#include <fmt/format.h>

#include "deflex/text/errors.hpp"
#include "deflex/text/parse_number.hpp"
#include "deflex/toolpath/detail/block_points.hpp"
#include "deflex/toolpath/detail/gcode_interpreter.hpp"
#include "deflex/toolpath/detail/line_reader.hpp"
#include "deflex/toolpath/toolpath_reader.hpp"

namespace deflex {

namespace detail {
/// One change to a line: bytes [begin, end) become `text` (an insertion when begin == end). Outside the
/// anonymous namespace: GcodeWriteBack::Impl keeps a vector of them.
struct GcodeLineEdit {
  std::size_t begin;
  std::size_t end;
  std::string text;
};
}  // namespace detail

namespace {

using detail::GcodeWord;
using LineEdit = detail::GcodeLineEdit;

int wb_code(const GcodeWord& w) { return static_cast<int>(std::lround(w.value * 10.0)); }

/// Writes `line` with `edits` applied into `out` (cleared first).
void wb_apply(std::string_view line, std::vector<LineEdit>& edits, std::string& out) {
  // By position; at one position the insertions first, so that a removal starting there follows them.
  std::stable_sort(edits.begin(), edits.end(), [](const LineEdit& a, const LineEdit& b) {
    if (a.begin != b.begin) return a.begin < b.begin;
    return (a.begin == a.end) && (b.begin != b.end);
  });
  out.clear();
  std::size_t at = 0;
  for (const LineEdit& e : edits) {
    out.append(line.substr(at, e.begin - at));
    out.append(e.text);
    at = e.end;
  }
  out.append(line.substr(at));
}

/// A value with `decimals` digits after the point, never "-0.000".
std::string wb_number(double v, int decimals) {
  char buffer[128];
  const auto r = std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::fixed, decimals);
  std::string_view s(buffer, static_cast<std::size_t>(r.ptr - buffer));  // |v| <= 1e5 in 100 decimals at most
  if (s.front() == '-' && s.find_first_not_of("-0.") == std::string_view::npos) {
    s.remove_prefix(1);
  }
  return std::string(s);
}

}  // namespace

struct GcodeWriteBack::Impl {
  std::string source;
  ToolpathOptions options;
  std::unique_ptr<OutputFile> own;
  OutputFile* out = nullptr;
  detail::LineReader lines;
  detail::GcodeInterpreter machine;
  detail::BlockPoints block;
  bool started = false;
  bool finished = false;
  std::string default_ending = "\n";
  bool ending_seen = false;
  // The motion line being written.
  std::string text;
  std::string ending;
  std::size_t line_number = 0;
  detail::GcodeLine words;
  detail::GcodeBlockFacts facts;
  std::size_t written = 0;  // points of the block written
  // The output's own modal state (differs from the source's after a rewritten arc or G91 block).
  int out_motion = -1;
  bool out_incremental = false;
  std::array<int, 26> decimals{};  // digits of the last number seen for each letter; 0: none seen
  std::vector<LineEdit> edits;     // reused from line to line
  std::string line_out;

  Impl(const std::string& src, const ToolpathOptions& o) : source(src), options(o), lines(src), machine(src, o) {}

  [[nodiscard]] int min_decimals(LengthUnit u) const { return u == LengthUnit::kInch ? 4 : 3; }
  [[nodiscard]] double scale(LengthUnit u) const { return u == LengthUnit::kInch ? 0.0254 : 1e-3; }

  void write(std::string_view bytes) { out->write(bytes); }

  void note_line(const detail::SourceLine& l) {
    if (!started) {
      started = true;
      if (lines.had_bom()) write("\xEF\xBB\xBF");
    }
    if (!ending_seen && !l.ending.empty()) {
      default_ending = std::string(l.ending);
      ending_seen = true;
    }
  }

  void note_words(const detail::GcodeLine& w) {
    for (const GcodeWord& word : w.words) {
      if (word.decimals >= 0 && word.index == 0) {
        decimals[static_cast<std::size_t>(word.letter - 'A')] = word.decimals;
      }
      if (word.letter != 'G' || word.index != 0) continue;
      const int c = wb_code(word);
      if (c == 0 || c == 10 || c == 20 || c == 30) out_motion = c / 10;
      if (c == 800) out_motion = -1;
      if (c == 900 || c == 910) out_incremental = c == 910;
    }
  }

  /// Copies lines until one that gives points; false at the end of the program.
  bool advance() {
    detail::SourceLine l;
    while (lines.next(l)) {
      note_line(l);
      const bool motion = machine.interpret(l, block);
      if (!motion) {
        note_words(machine.words());
        write(l.text);
        write(l.ending);
        continue;
      }
      text.assign(l.text);
      ending.assign(l.ending);
      line_number = l.number;
      words = machine.words();
      facts = machine.facts();
      written = 0;
      return true;
    }
    return false;
  }

  [[nodiscard]] int digits_for(char letter, const GcodeWord* w) const {
    const int seen = w != nullptr ? w->decimals : decimals[static_cast<std::size_t>(letter - 'A')];
    return std::max(seen, min_decimals(facts.units));
  }

  std::string position_words(const Vector3& p, bool compact) const {
    std::string s;
    for (int k = 0; k < 3; ++k) {
      const char letter = static_cast<char>('X' + k);
      if (!s.empty() && !compact) s += ' ';
      s += letter;
      s += wb_number(p[k] / scale(facts.units), digits_for(letter, nullptr));
    }
    return s;
  }

  /// The orientation words' values at a fraction of the block, in the block's own form.
  std::array<double, 3> orientation_at(const ToolpathPoint& p, double t) const {
    if (facts.orientation == detail::OrientationForm::kAngles) {
      const Vector3 a = facts.abc_start_deg + t * (facts.abc_end_deg - facts.abc_start_deg);
      return {a.x(), a.y(), a.z()};
    }
    return {p.tool_axis.x(), p.tool_axis.y(), p.tool_axis.z()};
  }

  /// The block's orientation words (pointers into `words`): A B C, or A3= B3= C3=, or I J K (G43.5).
  std::array<const GcodeWord*, 3> orientation_words() const {
    std::array<const GcodeWord*, 3> o{};
    for (const GcodeWord& w : words.words) {
      const bool angle =
          facts.orientation == detail::OrientationForm::kAngles && w.index == 0 && w.letter >= 'A' && w.letter <= 'C';
      const bool vec3 = facts.orientation == detail::OrientationForm::kVector && !facts.vector_by_ijk && w.index == 3;
      const bool ijk = facts.orientation == detail::OrientationForm::kVector && facts.vector_by_ijk && w.index == 0 &&
                       w.letter >= 'I' && w.letter <= 'K';
      if (angle || vec3) o[static_cast<std::size_t>(w.letter - 'A')] = &w;
      if (ijk) o[static_cast<std::size_t>(w.letter - 'I')] = &w;
    }
    return o;
  }

  const std::string& first_line(const ToolpathPoint& p, const Vector3& comp, double t);
  std::string extra_line(const ToolpathPoint& p, const Vector3& comp, double t) const;
  void add(const ToolpathPoint& point, const Vector3& comp);
  void finish();
};

const std::string& GcodeWriteBack::Impl::first_line(const ToolpathPoint& p, const Vector3& comp, double t) {
  edits.clear();
  const int desired = facts.motion_g == 0 ? 0 : 1;
  const GcodeWord* motion_word = nullptr;
  const GcodeWord* axis[3] = {};
  const GcodeWord* distance_word = nullptr;
  const bool arc = facts.motion_g == 2 || facts.motion_g == 3;
  for (const GcodeWord& w : words.words) {
    if (w.letter == 'G' && w.index == 0) {
      const int c = wb_code(w);
      if (c == 0 || c == 10 || c == 20 || c == 30) motion_word = &w;
      if (c == 910) distance_word = &w;
    } else if (w.index == 0 && w.letter >= 'X' && w.letter <= 'Z') {
      axis[w.letter - 'X'] = &w;
    } else if (arc && w.index == 0 && ((w.letter >= 'I' && w.letter <= 'K') || w.letter == 'R')) {
      // The arc's centre or radius goes with its G2/G3; the word and the blanks before it are removed.
      std::size_t b = w.begin;
      while (b > 0 && (text[b - 1] == ' ' || text[b - 1] == '\t')) --b;
      edits.push_back({b, w.end, ""});
    }
  }
  const std::string sep = words.compact ? "" : " ";
  // Where new leading words go: before the first word that is not a block number.
  std::size_t lead = 0;
  for (const GcodeWord& w : words.words) {
    if (w.letter != 'N') {
      lead = w.begin;
      break;
    }
  }
  std::string leading;
  if (distance_word != nullptr) {
    edits.push_back({distance_word->number_begin, distance_word->end, "90"});
  } else if (out_incremental) {
    leading += "G90" + sep;
  }
  if (motion_word != nullptr) {
    const std::string_view old =
        std::string_view(text).substr(motion_word->number_begin, motion_word->end - motion_word->number_begin);
    if (wb_code(*motion_word) / 10 != desired) {
      edits.push_back({motion_word->number_begin, motion_word->end,
                       old.size() >= 2 ? fmt::format("0{}", desired) : fmt::format("{}", desired)});
    }
  } else if (out_motion != desired) {
    leading += fmt::format("G{}", desired) + sep;
  }
  if (!leading.empty()) edits.push_back({lead, lead, leading});
  out_motion = desired;
  out_incremental = false;
  // A missing coordinate goes before the next present one, else after the previous one, else where
  // the motion's words begin: "Y5" becomes "X1.000 Y5.000 Z-2.000".
  for (int k = 0; k < 3; ++k) {
    const std::string value = wb_number(comp[k] / scale(facts.units), digits_for(static_cast<char>('X' + k), axis[k]));
    if (axis[k] != nullptr) {
      edits.push_back({axis[k]->number_begin, axis[k]->end, value});
      continue;
    }
    const std::string word = static_cast<char>('X' + k) + value;
    const GcodeWord* after = k + 1 < 3 && axis[k + 1] != nullptr ? axis[k + 1] : k + 2 < 3 ? axis[k + 2] : nullptr;
    const GcodeWord* before = k > 0 && axis[k - 1] != nullptr ? axis[k - 1] : k > 1 ? axis[k - 2] : nullptr;
    if (after != nullptr) {
      edits.push_back({after->begin, after->begin, word + sep});
    } else if (before != nullptr) {
      edits.push_back({before->end, before->end, sep + word});
    } else if (motion_word != nullptr) {
      edits.push_back({motion_word->end, motion_word->end, sep + word});
    } else {
      edits.push_back({lead, lead, word + sep});
    }
  }
  if (facts.orientation_changes && t < 1.0) {
    const auto values = orientation_at(p, t);
    const auto o = orientation_words();
    for (std::size_t k = 0; k < 3; ++k) {
      if (o[k] != nullptr) edits.push_back({o[k]->number_begin, o[k]->end, wb_number(values[k], 6)});
    }
  }
  wb_apply(text, edits, line_out);
  return line_out;
}

std::string GcodeWriteBack::Impl::extra_line(const ToolpathPoint& p, const Vector3& comp, double t) const {
  std::string s = position_words(comp, words.compact);
  if (facts.orientation_changes) {
    const auto values = orientation_at(p, t);
    const auto o = orientation_words();
    for (std::size_t k = 0; k < 3; ++k) {
      if (o[k] == nullptr) continue;
      if (!words.compact) s += ' ';
      s += std::string(o[k]->text(text).substr(0, o[k]->number_begin - o[k]->begin));
      s += wb_number(values[k], 6);
    }
  }
  return s;
}

void GcodeWriteBack::Impl::add(const ToolpathPoint& point, const Vector3& comp) {
  if (finished) throw InputError(fmt::format("{}: the compensated program is already finished", source));
  if (block.done() && !advance()) {
    throw InputError(
        fmt::format("{}: a compensated point for line {} after the program's last point", source, point.line));
  }
  ToolpathPoint expected;
  block.next(expected);
  machine.count_point(expected);
  if (expected.line != point.line || expected.segment != point.segment ||
      !((expected.position_m - point.position_m).norm() <= 1e-9)) {
    throw InputError(
        fmt::format("{}: the compensated points do not follow the program: its next point is on line "
                    "{} (block {}), the point given is from line {} (block {}); give the points "
                    "GcodeReader gives, with the same options, in order",
                    source, expected.line, expected.segment, point.line, point.segment));
  }
  if (!comp.allFinite() || comp.cwiseAbs().maxCoeff() > toolpath_limits::kMaxCoordinateM) {
    throw InputError(
        fmt::format("{}:{}: a compensated position that is not finite or beyond 100 m", source, point.line));
  }
  const double t = block.fraction();
  const bool last = block.done();
  const std::string& sep_ending = ending.empty() ? default_ending : ending;
  if (written == 0) {
    write(first_line(expected, comp, t));
  } else {
    write(extra_line(expected, comp, t));
  }
  write(last ? std::string_view(ending) : std::string_view(sep_ending));
  ++written;
}

void GcodeWriteBack::Impl::finish() {
  if (finished) return;
  if (!block.done()) {
    throw InputError(
        fmt::format("{}:{}: the compensated points end inside the block of line {}: every point of "
                    "the program needs its compensated position",
                    source, line_number, line_number));
  }
  if (advance()) {
    throw InputError(
        fmt::format("{}:{}: the compensated points end before the program's motion on line {}: every "
                    "point of the program needs its compensated position",
                    source, line_number, line_number));
  }
  finished = true;
  if (own) own->commit();
}

namespace {

void refuse_same_file(const std::string& source, const std::string& output) {
  if (toolpath_format_for(source) != ToolpathFormat::kGcode) {
    throw InputError(
        fmt::format("{}: the compensated program is written as G-code, from a G-code program; this "
                    "toolpath is APT/CL data",
                    source));
  }
  std::error_code ec;
  if (std::filesystem::exists(output, ec) && std::filesystem::equivalent(source, output, ec)) {
    throw InputError(
        fmt::format("{}: the compensated program would overwrite the program it is made from ({}): "
                    "write it to another file",
                    output, source));
  }
}

}  // namespace

GcodeWriteBack::GcodeWriteBack(const std::string& source_path, const std::string& output_path,
                               const ToolpathOptions& options, const std::string& what) {
  refuse_same_file(source_path, output_path);
  impl_ = std::make_unique<Impl>(source_path, options);
  impl_->own = std::make_unique<OutputFile>(output_path, what);
  impl_->out = impl_->own.get();
}

GcodeWriteBack::GcodeWriteBack(const std::string& source_path, OutputFile& output, const ToolpathOptions& options) {
  refuse_same_file(source_path, output.path());
  impl_ = std::make_unique<Impl>(source_path, options);
  impl_->out = &output;
}

GcodeWriteBack::~GcodeWriteBack() = default;

void GcodeWriteBack::add(const ToolpathPoint& point, const Vector3& compensated_position_m) {
  impl_->add(point, compensated_position_m);
}

void GcodeWriteBack::finish() { impl_->finish(); }

}  // namespace deflex
