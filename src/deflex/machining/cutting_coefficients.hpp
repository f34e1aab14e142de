// The cutting and edge coefficients of the linear edge-force milling model, from the force spec
// ("milling:Ktc_N_mm2=..,...", "milling:file=COEFFS.yaml") or a coefficient file, with the checks that
// keep a typo or a unit slip out of the force.
#pragma once

#include <optional>
#include <string>

namespace deflex {

/// Per unit of chip area (cutting, N/m^2) and per unit of edge length (edge, N/m): the tangential,
/// radial and axial force on one tooth's slice is  b (Kc h + Ke)  (milling_force.hpp). SI inside:
/// 1 N/mm^2 = 1e6 N/m^2, 1 N/mm = 1e3 N/m.
struct CuttingCoefficients {
  double ktc_n_m2 = 0.0;
  double krc_n_m2 = 0.0;
  double kac_n_m2 = 0.0;
  double kte_n_m = 0.0;
  double kre_n_m = 0.0;
  double kae_n_m = 0.0;
};

/// A coefficient set with what it is for and where it came from (a coefficient file's metadata).
struct CoefficientSet {
  CuttingCoefficients k;
  std::string source;    ///< publication, or the fit's logs
  std::string material;  ///< "Al7075-T6"
  std::string tool;      ///< "carbide end mill, 3 flutes, 30 deg helix"
  std::string note;
  /// Standard errors of a fitted set, same units (absent for a published set).
  std::optional<CuttingCoefficients> standard_error;
};

/// The accepted ranges (cutting_coefficients.cpp says why), in the units users write.
namespace coefficient_limits {
inline constexpr double kMinKtcNmm2 = 10.0;    // below: not a metal, nor a plastic worth a force model
inline constexpr double kMaxKcNmm2 = 20000.0;  // above every metal's specific cutting force
inline constexpr double kMaxKeNmm = 1000.0;    // 1 kN per mm of edge: no edge rubs that hard
}  // namespace coefficient_limits

/// The names users write, in the order of the struct: Ktc_N_mm2, Krc_N_mm2, Kac_N_mm2, Kte_N_mm,
/// Kre_N_mm, Kae_N_mm.
inline constexpr const char* kCoefficientKeys[6] = {"Ktc_N_mm2", "Krc_N_mm2", "Kac_N_mm2",
                                                    "Kte_N_mm",  "Kre_N_mm",  "Kae_N_mm"};

/// A coefficient by its index in kCoefficientKeys, in the unit of its key (N/mm^2 or N/mm).
[[nodiscard]] double coefficient_in_user_units(const CuttingCoefficients& k, int index);
void set_coefficient_from_user_units(CuttingCoefficients& k, int index, double value);

/// Throws InputError "WHAT: Kre_N_mm: -3 N/mm is outside 0..1000 N/mm (...)" for the first value out
/// of range (NaN included).
void validate_coefficients(const CuttingCoefficients& k, const std::string& what);

/// Reads a coefficient file (YAML): the six keys (required), source (required), material, tool,
/// note, standard_error (a map of the six keys). Any other key, a missing one, a value out of range
/// or a standard error below 0 is a ModelError naming the file, the line and the key.
[[nodiscard]] CoefficientSet read_coefficient_file(const std::string& path);

/// The YAML text of a coefficient file read_coefficient_file() reads back; `comment` (several lines
/// allowed) goes first as '#' lines.
[[nodiscard]] std::string coefficient_file_text(const CoefficientSet& set, const std::string& comment = "");

/// How the side of the material is chosen when an ae override replaces the stock's engagement.
enum class OverrideCut {
  kClimb,         ///< down milling: the teeth leave the material where the chip is thinnest
  kConventional,  ///< up milling: the teeth enter where the chip is thinnest
};

/// The body of a "milling:..." force spec.
struct MillingSpec {
  CoefficientSet coefficients;
  std::optional<double> ae_m;  ///< radial width override for the whole run
  std::optional<double> ap_m;  ///< axial depth override for the whole run
  OverrideCut cut = OverrideCut::kClimb;
  std::string file;  ///< the coefficient file, when one was given
};

/// Parses "milling:Ktc_N_mm2=..,Krc_N_mm2=..,Kac_N_mm2=..,Kte_N_mm=..,Kre_N_mm=..,Kae_N_mm=..
/// [,ae_mm=..][,ap_mm=..][,cut=climb|conventional]" or "milling:file=COEFFS.yaml[,ae_mm=..]
/// [,ap_mm=..][,cut=..]" (the "milling:" prefix optional). The six coefficients are all required
/// unless a file gives them; a file and coefficient keys together are refused; cut= needs ae_mm=.
/// ae_mm in 0..300 mm and ap_mm in 0..1000 mm (exclusive of 0); a check against the cutter's diameter
/// is the caller's (check_overrides()). Throws InputError quoting the spec and naming the key, or
/// ModelError naming the file.
[[nodiscard]] MillingSpec parse_milling_spec(const std::string& spec);

struct Cutter;
/// Throws InputError when ae_mm exceeds the cutter's diameter.
void check_overrides(const MillingSpec& spec, const Cutter& cutter);

}  // namespace deflex
