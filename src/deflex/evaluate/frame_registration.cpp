// Tracker-to-base registration (see frame_registration.hpp).
#include "deflex/evaluate/frame_registration.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

#include <fmt/format.h>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "deflex/evaluate/tracker_files.hpp"
#include "deflex/model/linear_algebra.hpp"
#include "deflex/text/errors.hpp"
#include "deflex/text/yaml_fields.hpp"

namespace deflex {
namespace {

bool finite_all(const std::vector<Vector3>& v) {
  return std::all_of(v.begin(), v.end(), [](const Vector3& p) { return p.allFinite(); });
}

// No rotation maps a mirror image onto its original (the tracker's points against base points whose
// frame has an axis reversed, or a CSV whose y column was negated): Horn's method still returns its
// best rotation, with a residual of the order of the point spread. The best orthogonal map of the
// cross-covariance S = U diag V^T is V U^T; when that is a reflection and it fits at under a third
// of the rotation's RMS, the pairs are mirrored, not noisy.
void refuse_mirror_image(const Matrix3& S, const std::vector<Vector3>& a, const std::vector<Vector3>& b,
                         const Vector3& ca, const Vector3& cb, double rms_rotation_m) {
  const Eigen::JacobiSVD<Matrix3> svd(S, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Matrix3 q = svd.matrixV() * svd.matrixU().transpose();
  if (!(q.determinant() < 0.0)) return;
  double ss = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) ss += (q * (a[i] - ca) - (b[i] - cb)).squaredNorm();
  const double rms_reflection_m = std::sqrt(ss / static_cast<double>(a.size()));
  if (!(3.0 * rms_reflection_m < rms_rotation_m)) return;
  throw InputError(fmt::format(
      "registration: the base points are a mirror image of the tracker points: the best rotation leaves an RMS of "
      "{:.4f} mm, a reflection would fit them to {:.4f} mm. No robot base is a reflection of a tracker frame: one "
      "file's frame is left-handed or has an axis reversed (a coordinate's sign flipped on export), or the points "
      "are paired with their mirror images",
      rms_rotation_m * 1e3, rms_reflection_m * 1e3));
}

// A frame fitted through pairs that do not belong together is a wrong frame, however well its
// residuals are printed: above the limit it is refused, naming the worst points.
void refuse_large_rms(const FrameRegistration& r, double max_rms_m) {
  if (!(max_rms_m > 0.0)) {
    throw InputError(fmt::format("registration: the RMS limit must be a positive length, not {} m", max_rms_m));
  }
  if (r.rms_m <= max_rms_m) return;
  std::vector<const RegistrationResidual*> worst;
  for (const auto& e : r.residuals) worst.push_back(&e);
  std::sort(worst.begin(), worst.end(), [](const auto* x, const auto* y) { return x->distance_m > y->distance_m; });
  std::string list;
  for (std::size_t k = 0; k < std::min<std::size_t>(3, worst.size()); ++k) {
    list += fmt::format("{}{} {:.4f} mm", k == 0 ? "" : ", ", worst[k]->name, worst[k]->distance_m * 1e3);
  }
  throw InputError(fmt::format(
      "registration: RMS {:.4f} mm is above the limit of {:.4f} mm (largest residuals: {}): points paired with the "
      "wrong partners, a unit slip or a nest that moved; the frame is not written. If the base points are only "
      "known this well (a robot's absolute accuracy), raise the limit (deflex register --max-rms-mm)",
      r.rms_m * 1e3, max_rms_m * 1e3, list));
}

}  // namespace

CircleFit fit_circle(const std::vector<Vector3>& points, const std::string& what) {
  if (points.size() < 5) {
    throw InputError(fmt::format("{}: {} point(s); a circle fit needs at least 5", what, points.size()));
  }
  if (!finite_all(points)) throw InputError(fmt::format("{}: a point is not finite", what));
  Vector3 centroid = Vector3::Zero();
  for (const auto& p : points) centroid += p;
  centroid /= static_cast<double>(points.size());
  Matrix3 cov = Matrix3::Zero();
  for (const auto& p : points) cov += (p - centroid) * (p - centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(cov);  // eigenvalues ascending
  const Vector3 sv = eig.eigenvalues().cwiseMax(0.0).cwiseSqrt();
  if (!(sv[1] > 1e-3 * sv[2])) {
    throw InputError(fmt::format("{}: the points lie on a line, not on a circle", what));
  }
  Vector3 normal = eig.eigenvectors().col(0);
  const Vector3 u = eig.eigenvectors().col(2);
  const Vector3 v = normal.cross(u);
  // Algebraic (Kasa) fit in the plane: x^2 + y^2 = 2 a x + 2 b y + c.
  const auto n = static_cast<Eigen::Index>(points.size());
  Eigen::MatrixXd A(n, 3);
  Eigen::VectorXd rhs(n);
  std::vector<Eigen::Vector2d> xy(points.size());
  for (Eigen::Index i = 0; i < n; ++i) {
    const Vector3 d = points[static_cast<std::size_t>(i)] - centroid;
    xy[static_cast<std::size_t>(i)] = {d.dot(u), d.dot(v)};
    A.row(i) << 2 * d.dot(u), 2 * d.dot(v), 1.0;
    rhs[i] = d.dot(u) * d.dot(u) + d.dot(v) * d.dot(v);
  }
  const Eigen::Vector3d abc = A.colPivHouseholderQr().solve(rhs);
  Eigen::Vector2d c(abc[0], abc[1]);
  double r = std::sqrt(std::max(0.0, abc[2] + c.squaredNorm()));
  // Gauss-Newton on the geometric distances |p - c| - r (the algebraic fit is biased on short arcs).
  for (int it = 0; it < 20; ++it) {
    Eigen::MatrixXd J(n, 3);
    Eigen::VectorXd res(n);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Vector2d d = xy[static_cast<std::size_t>(i)] - c;
      const double dist = std::max(d.norm(), 1e-12);
      res[i] = dist - r;
      J.row(i) << -d.x() / dist, -d.y() / dist, -1.0;
    }
    const Eigen::Vector3d step = J.colPivHouseholderQr().solve(-res);
    c += step.head<2>();
    r += step[2];
    if (step.norm() < 1e-12) break;
  }
  CircleFit fit;
  fit.points = points.size();
  fit.radius_m = r;
  double ss = 0.0, swept = 0.0, turned = 0.0;
  double min_a = 0.0, max_a = 0.0;
  for (std::size_t i = 0; i < xy.size(); ++i) {
    const double e = (xy[i] - c).norm() - r;
    ss += e * e;
    if (i > 0) {
      const Eigen::Vector2d a = xy[i - 1] - c, b = xy[i] - c;
      const double da = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));
      swept += a.x() * b.y() - a.y() * b.x();
      turned += da;
      min_a = std::min(min_a, turned);
      max_a = std::max(max_a, turned);
    }
  }
  fit.rms_m = std::sqrt(ss / static_cast<double>(xy.size()));
  fit.arc_rad = std::min(2 * kPi, max_a - min_a);
  if (fit.arc_rad < 20.0 * kPi / 180.0) {
    throw InputError(
        fmt::format("{}: the points span {:.1f} degrees of arc; at least 20 are needed for a centre and "
                    "axis worth registering with",
                    what, fit.arc_rad * 180.0 / kPi));
  }
  if (swept < 0.0) normal = -normal;  // right-hand rule along the direction of travel
  fit.axis = normal;
  fit.centre_m = centroid + c.x() * u + c.y() * v;
  return fit;
}

namespace {

// The pairs must pair up, be finite and be enough to fix a frame.
void check_registration_input(const RegistrationInput& in) {
  if (in.tracker_m.size() != in.base_m.size()) {
    throw InputError(fmt::format("registration: {} tracker point(s) and {} base point(s): they must pair up",
                                 in.tracker_m.size(), in.base_m.size()));
  }
  if (in.tracker_circles.size() != in.base_circles.size()) {
    throw InputError(fmt::format("registration: {} tracker circle(s) and {} base circle(s): they must pair up",
                                 in.tracker_circles.size(), in.base_circles.size()));
  }
  if (!finite_all(in.tracker_m) || !finite_all(in.base_m)) throw InputError("registration: a point is not finite");
  const std::size_t np = in.tracker_m.size(), nc = in.tracker_circles.size();
  if (np + nc == 0 || (nc == 0 && np < 3)) {
    throw InputError(
        fmt::format("registration: {} point pair(s) and no circle: at least 3 points off one line are "
                    "needed (or circles)",
                    np));
  }
}

// The rotation that best maps the tracker's features onto the base's, from their correlation S (the
// sum of a' b'^T): the unit quaternion of N(S)'s largest eigenvalue (Horn's closed form, 1987).
Matrix3 rotation_from_correlation(const Matrix3& S) {
  Eigen::Matrix4d N;
  const double sxx = S(0, 0), sxy = S(0, 1), sxz = S(0, 2), syx = S(1, 0), syy = S(1, 1), syz = S(1, 2);
  const double szx = S(2, 0), szy = S(2, 1), szz = S(2, 2);
  N << sxx + syy + szz, syz - szy, szx - sxz, sxy - syx,  //
      syz - szy, sxx - syy - szz, sxy + syx, szx + sxz,   //
      szx - sxz, sxy + syx, -sxx + syy - szz, syz + szy,  //
      sxy - syx, szx + sxz, syz + szy, -sxx - syy + szz;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(N);
  const Eigen::Vector4d q = eig.eigenvectors().col(3);  // largest eigenvalue last
  const Eigen::Quaterniond quat(q[0], q[1], q[2], q[3]);
  return quat.normalized().toRotationMatrix();
}

}  // namespace

FrameRegistration register_frames(const RegistrationInput& in) {
  check_registration_input(in);
  const std::size_t np = in.tracker_m.size(), nc = in.tracker_circles.size();
  // Every point feature: the measured points and the circles' centres.
  std::vector<Vector3> a = in.tracker_m, b = in.base_m;
  std::vector<std::string> names(np);
  for (std::size_t i = 0; i < np; ++i) names[i] = i < in.names.size() ? in.names[i] : fmt::format("point {}", i + 1);
  for (std::size_t k = 0; k < nc; ++k) {
    a.push_back(in.tracker_circles[k].centre_m);
    b.push_back(in.base_circles[k].centre_m);
    names.push_back(fmt::format("circle {} centre", k + 1));
  }
  Vector3 ca = Vector3::Zero(), cb = Vector3::Zero();
  for (std::size_t i = 0; i < a.size(); ++i) {
    ca += a[i];
    cb += b[i];
  }
  ca /= static_cast<double>(a.size());
  cb /= static_cast<double>(b.size());
  Matrix3 S = Matrix3::Zero();  // sum of a' b'^T
  Eigen::Matrix<double, 3, Eigen::Dynamic> spread(3, static_cast<Eigen::Index>(a.size() + nc));
  for (std::size_t i = 0; i < a.size(); ++i) {
    S += (a[i] - ca) * (b[i] - cb).transpose();
    spread.col(static_cast<Eigen::Index>(i)) = a[i] - ca;
  }
  for (std::size_t k = 0; k < nc; ++k) {
    const double w = in.tracker_circles[k].radius_m * in.base_circles[k].radius_m;
    S += w * in.tracker_circles[k].axis * in.base_circles[k].axis.transpose();
    spread.col(static_cast<Eigen::Index>(a.size() + k)) = std::sqrt(w) * in.tracker_circles[k].axis;
  }
  // The rotation is fixed only if the features span at least two directions.
  const Eigen::VectorXd sv = singular_values(spread);
  if (sv.size() < 2 || !(sv[1] > 1e-3 * sv[0])) {
    throw InputError(
        "registration: the points lie on one line (and no circle axis leaves it): the rotation about that line is "
        "not fixed; measure a point off the line");
  }
  FrameRegistration out;
  out.base_T_tracker.linear() = rotation_from_correlation(S);
  out.base_T_tracker.translation() = cb - out.base_T_tracker.linear() * ca;
  double ss = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double d = (out.base_T_tracker * a[i] - b[i]).norm();
    out.residuals.push_back({names[i], d});
    ss += d * d;
    out.max_m = std::max(out.max_m, d);
  }
  out.rms_m = std::sqrt(ss / static_cast<double>(a.size()));
  for (std::size_t k = 0; k < nc; ++k) {
    const Vector3 ra = out.base_T_tracker.linear() * in.tracker_circles[k].axis;
    out.circle_axis_error_rad.push_back(std::acos(std::clamp(ra.dot(in.base_circles[k].axis), -1.0, 1.0)));
  }
  out.points = np;
  out.circles = nc;
  refuse_mirror_image(S, a, b, ca, cb, out.rms_m);
  refuse_large_rms(out, in.max_rms_m);
  return out;
}

void write_tracker_frame(const TrackerFrame& f, OutputFile& out) {
  const Eigen::Quaterniond q(f.base_T_tracker.linear());
  const Vector3 t = f.base_T_tracker.translation();
  std::string text =
      "# deflex tracker frame: p_base = base_T_tracker * p_tracker (position in m, unit quaternion w x y z).\n"
      "# Written by deflex register; read by deflex evaluate --tracker-frame.\n";
  text += fmt::format("tracker_frame: {}\n", yaml::scalar_text(f.tracker_frame));
  text += "base_T_tracker:\n";
  text += fmt::format("  position: [{:.9f}, {:.9f}, {:.9f}]\n", t.x(), t.y(), t.z());
  text += fmt::format("  quaternion_wxyz: [{:.15f}, {:.15f}, {:.15f}, {:.15f}]\n", q.w(), q.x(), q.y(), q.z());
  text += "registration:\n";
  text += fmt::format("  points: {}\n  circles: {}\n", f.points, f.circles);
  if (std::isfinite(f.rms_m)) text += fmt::format("  rms_mm: {:.6f}\n  max_mm: {:.6f}\n", f.rms_m * 1e3, f.max_m * 1e3);
  if (std::isfinite(f.rms_limit_m)) text += fmt::format("  rms_limit_mm: {:.6f}\n", f.rms_limit_m * 1e3);
  out.write(text);
}

TrackerFrame read_tracker_frame(const std::string& path) {
  const yaml::Field root = yaml::Field::load_file(path);
  root.only_keys({"tracker_frame", "base_T_tracker", "registration"});
  TrackerFrame f;
  f.tracker_frame = root.get("tracker_frame", std::string());
  f.base_T_tracker = yaml::parse_pose(root.at("base_T_tracker"), 1.0, 1.0);
  if (!root.at("base_T_tracker").has("quaternion_wxyz") && !root.at("base_T_tracker").has("rpy")) {
    root.at("base_T_tracker").fail("no rotation (quaternion_wxyz): a tracker frame is never only a translation");
  }
  if (root.has("registration")) {
    const yaml::Field r = root.at("registration");
    r.only_keys({"points", "circles", "rms_mm", "max_mm", "rms_limit_mm"});
    f.points = static_cast<std::size_t>(std::max(0, r.get("points", 0)));
    f.circles = static_cast<std::size_t>(std::max(0, r.get("circles", 0)));
    if (r.has("rms_mm")) f.rms_m = r.at("rms_mm").as_double() * 1e-3;
    if (r.has("max_mm")) f.max_m = r.at("max_mm").as_double() * 1e-3;
    if (r.has("rms_limit_mm")) f.rms_limit_m = r.at("rms_limit_mm").as_in(range::kPositiveLengthMm) * 1e-3;
    // A frame file written by hand or by an older register with a failed registration in it.
    const double limit = std::isfinite(f.rms_limit_m) ? f.rms_limit_m : kDefaultMaxRegistrationRmsM;
    if (r.has("rms_mm") && !(f.rms_m <= limit)) {
      r.at("rms_mm").fail(fmt::format(
          "the registration's RMS {:.4f} mm is above its limit of {:.4f} mm: the frame failed and is not used "
          "(register again, or with deflex register --max-rms-mm if the points are known only this well)",
          f.rms_m * 1e3, limit * 1e3));
    }
  }
  return f;
}

namespace {

// The target's own name: the last part of "Collection::Group::Target".
std::string target_of(const std::string& name) {
  const auto at = name.rfind("::");
  return at == std::string::npos ? name : name.substr(at + 2);
}

std::string whole_name(const std::string& name) { return name; }

// "FILE:LINE" of a point, or FILE alone for a point not read from a file.
std::string point_place(const TrackerFile& f, const TrackerPoint& p) {
  return p.line > 0 ? fmt::format("{}:{}", f.source, p.line) : f.source;
}

// Pairs by the key `key_of` gives each point: every key once on each side, and the same keys on both.
// Returns false (and pairs nothing) when the key sets differ; throws for a repeated key.
bool pair_by(const TrackerFile& t, const TrackerFile& b, std::string (*key_of)(const std::string&),
             RegistrationInput& in) {
  std::map<std::string, const TrackerPoint*> base, tracker;
  for (const auto* f : {&b, &t}) {
    auto& into = f == &b ? base : tracker;
    for (const auto& p : f->points) {
      if (!into.emplace(key_of(p.name), &p).second) {
        throw DataError(fmt::format("{}: point '{}' named twice", point_place(*f, p), key_of(p.name)));
      }
    }
  }
  for (const auto& [key, p] : tracker) {
    if (base.count(key) == 0) return false;
  }
  if (base.size() != tracker.size()) return false;
  for (const auto& p : t.points) {
    in.tracker_m.push_back(p.p_m);
    in.base_m.push_back(base.at(key_of(p.name))->p_m);
    in.names.push_back(key_of(p.name));
  }
  return true;
}

// Both files name their points but the names do not pair: the first point of either without a
// partner, named with its file and line.
[[noreturn]] void throw_unpaired(const TrackerFile& t, const TrackerFile& b) {
  std::set<std::string> base;
  for (const auto& p : b.points) base.insert(target_of(p.name));
  for (const auto& p : t.points) {
    if (base.count(target_of(p.name)) == 0) {
      throw DataError(
          fmt::format("{}: point '{}' is not in {} (pairs are made by name)", point_place(t, p), p.name, b.source));
    }
    base.erase(target_of(p.name));
  }
  for (const auto& p : b.points) {
    if (base.count(target_of(p.name)) != 0) {
      throw DataError(
          fmt::format("{}: point '{}' is not in {} (pairs are made by name)", point_place(b, p), p.name, t.source));
    }
  }
  throw DataError(fmt::format("{} and {}: the point names do not pair", t.source, b.source));
}

}  // namespace

RegistrationInput pair_tracker_points(const TrackerFile& t, const TrackerFile& b) {
  RegistrationInput in;
  if (t.has_names && b.has_names) {
    if (pair_by(t, b, whole_name, in) || pair_by(t, b, target_of, in)) return in;
    throw_unpaired(t, b);
  }
  if (t.points.size() != b.points.size()) {
    throw DataError(
        fmt::format("{} has {} point(s) and {} has {}: without names on both sides they pair by order and "
                    "must be as many",
                    t.source, t.points.size(), b.source, b.points.size()));
  }
  for (std::size_t i = 0; i < t.points.size(); ++i) {
    in.tracker_m.push_back(t.points[i].p_m);
    in.base_m.push_back(b.points[i].p_m);
    const std::string where = t.points[i].line > 0 ? fmt::format("point {} (line {})", i + 1, t.points[i].line)
                                                   : fmt::format("point {}", i + 1);
    in.names.push_back(t.has_names ? t.points[i].name : where);
  }
  return in;
}

}  // namespace deflex
