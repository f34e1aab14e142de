// How an RDT sensor's counts become newtons and newton-metres, and at what rate it streams: from the
// configuration page the sensor serves (ATI Net F/T and Axia: netftapi2.xml, given as a file or
// fetched over HTTP), from explicit counts per unit, or from OnRobot HEX's fixed scaling. The units
// the sensor is configured in are read and converted, never assumed (the drivers that assume
// 1,000,000 counts per N give wrong forces on any other calibration). Set-up time only: everything
// here allocates and throws; the force source keeps the two scale factors it needs.
#pragma once

#include <string>

namespace deflex {

/// The newtons of one force unit as the ATI manuals name them (9620-05, configuration page: lbf, N,
/// klbf, kN, kgf, gf; also spelled with case or separators changed, "KN"), 0 when unknown.
[[nodiscard]] double newtons_per_force_unit(const std::string& unit);
/// The newton-metres of one torque unit (lbf-in, lbf-ft, N-m, N-mm, kgf-cm, kN-m; "Nm", "Nmm" ...),
/// 0 when unknown.
[[nodiscard]] double newton_metres_per_torque_unit(const std::string& unit);
/// The manuals' numeric unit codes (cfgfu, cfgtu: 1..6) as the names above; "" when unknown.
[[nodiscard]] std::string force_unit_of_code(int code);
[[nodiscard]] std::string torque_unit_of_code(int code);

struct RdtCalibration {
  std::string source = "<none>";   ///< where it came from (file, URL, "options", "profile onrobot-hex")
  std::string sensor_name;         ///< the product and serial the page names, or the profile's name
  double counts_per_force = 0.0;   ///< counts per `force_unit` (cfgcpf)
  double counts_per_torque = 0.0;  ///< counts per `torque_unit` (cfgcpt)
  std::string force_unit = "N";    ///< as the sensor names it (scfgfu)
  std::string torque_unit = "Nm";  ///< (scfgtu)
  double rate_hz = 0.0;            ///< records a second the sensor streams (comrdtrate); 0: not known yet
  int buffer_records = 0;          ///< records a datagram in buffered mode (comrdtbsiz); 0: not stated
  double internal_rate_hz = 0.0;   ///< the sensor's own sampling rate (runrate), for the log; 0: not stated
  bool onrobot = false;            ///< OnRobot Compute Box: the rate is set by command 0x0082 at start

  /// Throws InputError naming `source` and the field when a count is missing or not positive, a unit
  /// is unknown, or the rate is not known or not positive.
  void validate() const;
  /// N a count and Nm a count (validate() first).
  [[nodiscard]] double force_n_per_count() const;
  [[nodiscard]] double torque_nm_per_count() const;
  /// "ATI FT12345: 1000000 counts/N, 1000000 counts/Nm, 1000 Hz (netftapi2.xml at ...)".
  [[nodiscard]] std::string describe() const;
};

/// Reads the calibration from the text of a netftapi2.xml page. `origin` (a path or URL) starts every
/// message: "ORIGIN:LINE: field 'cfgcpf': ...". Reads cfgcpf, cfgcpt (required, positive), the units
/// scfgfu / scfgtu (or the codes cfgfu / cfgtu; when both are given they must agree), comrdtrate,
/// comrdtbsiz, runrate, prodname / cfgcalsn (optional). Throws ModelError on a malformed page, a
/// missing or non-positive count or an unknown unit. The rate may be missing (rate_hz = 0): the caller
/// then needs it from elsewhere (resolve_rdt_calibration).
[[nodiscard]] RdtCalibration parse_netft_xml(const std::string& text, const std::string& origin);
/// The same from a file. Throws DataError naming the path when it cannot be read.
[[nodiscard]] RdtCalibration load_netft_xml(const std::string& path);
/// The same fetched over HTTP (http_fetch.hpp). Throws Error naming the URL when the sensor does not
/// answer in `timeout_s`.
[[nodiscard]] RdtCalibration fetch_netft_xml(const std::string& url, double timeout_s);

/// OnRobot HEX-E/H through its Compute Box: force = counts / 10000 N, torque = counts / 100000 Nm
/// (OnRobot's example highspeed_udp.c). The Compute Box's output rate is 1000 / n Hz (command 0x0082
/// with n): `rate_hz` must be one of those (1000, 500, 333.33.., 250 ...), else InputError.
[[nodiscard]] RdtCalibration onrobot_hex_calibration(double rate_hz);

/// What a command line gives for an rdt force source's calibration.
struct RdtCalibrationOptions {
  /// One of: "sensor" (fetch http://HOST/netftapi2.xml from the sensor itself), a path to a saved
  /// netftapi2.xml, an http:// URL of one, "onrobot-hex", or
  /// "counts:counts_per_force=C,counts_per_torque=C,force_unit=U,torque_unit=U". Empty: refused.
  std::string spec;
  double rate_hz = 0.0;         ///< the RDT output rate; 0: from the page (required for "counts:")
  double http_timeout_s = 2.0;  ///< for "sensor" and URLs
};

/// The calibration the options name, validated. `sensor_host` is the sensor's address (for "sensor").
/// A rate given both in the options and on the page must agree (within 0.5 %): the page is the
/// sensor's own setting, and a filter designed for another rate would be wrong. Throws InputError
/// (empty or unknown spec, rate disagreement, missing rate), ModelError (a bad page) or Error (no answer).
[[nodiscard]] RdtCalibration resolve_rdt_calibration(const RdtCalibrationOptions& options,
                                                     const std::string& sensor_host);

}  // namespace deflex
