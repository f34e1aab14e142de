// EGM codec over the protoc-generated classes (egm.proto).
#include "deflex/wire/egm_codec.hpp"

#include <atomic>
#include <cmath>
#include <mutex>

#include <google/protobuf/stubs/logging.h>

#include "deflex/wire/detail/egm_fast.hpp"
#include "egm.pb.h"

namespace deflex {

const char* to_string(EgmDecodeStatus s) {
  switch (s) {
    case EgmDecodeStatus::kOk:
      return "ok";
    case EgmDecodeStatus::kMalformed:
      return "malformed";
    case EgmDecodeStatus::kTruncated:
      return "truncated";
    case EgmDecodeStatus::kMissingHeader:
      return "missing_header";
    case EgmDecodeStatus::kMissingJoints:
      return "missing_joints";
    case EgmDecodeStatus::kNonFinite:
      return "non_finite";
    case EgmDecodeStatus::kEmpty:
      return "empty";
    case EgmDecodeStatus::kSequenceOutOfRange:
      return "sequence_out_of_range";
    case EgmDecodeStatus::kMissingRequired:
      return "missing_required";
  }
  return "unknown";
}

// Protobuf decodes what the hand-written reader does not take (detail/egm_fast.hpp) and codes path
// correction; the joint-mode messages are written by hand, to protobuf's bytes.
struct EgmCodec::Impl {
  abb::egm::EgmRobot robot_in;
  abb::egm::EgmSensor sensor_in;
  abb::egm::EgmSensorPathCorr path_in, path_out;
  // Protobuf's reused EgmSensor kept an empty speedRef.joints once it had sent a speed reference;
  // the hand-written encoder keeps the same bytes.
  bool speed_ref_sent = false;
};

namespace {

template <class Joints>
bool copy_joints(const Joints& j, int expected, JointVector& out) {
  if (j.joints_size() != expected) {
    return false;
  }
  out.resize(expected);
  for (int i = 0; i < expected; ++i) {
    out[i] = j.joints(i);
  }
  return true;
}

// EgmHeader.seqno (field 1 of the header, field 1 of EgmRobot) as the varint says it: protobuf would
// keep only its low 32 bits. False when any occurrence is wider than 32 bits. The top level has been
// scanned already; a header that is itself garbled is left to protobuf to refuse.
bool header_seqno_fits(const unsigned char* data, std::size_t size) {
  const unsigned char* p = data;
  const unsigned char* end = data + size;
  while (p < end) {
    std::uint64_t tag = 0, len = 0;
    bool bad = false;
    if (!egm_fast::read_varint(p, end, tag, bad) || bad) return true;
    switch (tag & 7) {
      case 0:
        if (!egm_fast::read_varint(p, end, len, bad) || bad) return true;
        break;
      case 1:
        p += 8;
        break;
      case 5:
        p += 4;
        break;
      case 2: {
        if (!egm_fast::read_varint(p, end, len, bad) || bad || len > static_cast<std::uint64_t>(end - p)) return true;
        const unsigned char* h = p;
        const unsigned char* h_end = p + len;
        p = h_end;
        if ((tag >> 3) != 1) break;
        while (h < h_end) {
          std::uint64_t htag = 0, value = 0;
          if (!egm_fast::read_varint(h, h_end, htag, bad) || bad) break;
          if ((htag & 7) != 0) break;  // seqno and tm are varints; anything else is protobuf's to judge
          if (!egm_fast::read_varint(h, h_end, value, bad) || bad) break;
          if ((htag >> 3) == 1 && value > 0xFFFFFFFFULL) return false;
        }
        break;
      }
      default:
        return true;
    }
  }
  return true;
}

std::atomic<std::uint64_t> g_protobuf_log_messages{0};

void count_protobuf_log(google::protobuf::LogLevel /*level*/, const char* /*filename*/, int /*line*/,
                        const std::string& /*message*/) {
  g_protobuf_log_messages.fetch_add(1, std::memory_order_relaxed);
}

}  // namespace

std::uint64_t egm_protobuf_log_messages() noexcept { return g_protobuf_log_messages.load(std::memory_order_relaxed); }

std::uint32_t egm_time_stamp_ms(double t_s) noexcept {
  if (!std::isfinite(t_s) || !(t_s > 0.0)) {
    return 0;
  }
  const double ms = std::fmod(std::floor(t_s * 1000.0), 4294967296.0);  // exact: doubles hold 2^53
  return static_cast<std::uint32_t>(ms);
}

EgmDecodeStatus scan_wire_format(const unsigned char* data, std::size_t size) noexcept {
  const unsigned char* p = data;
  const unsigned char* end = data + size;
  while (p < end) {
    std::uint64_t tag = 0;
    bool bad = false;
    if (!egm_fast::read_varint(p, end, tag, bad)) {
      return EgmDecodeStatus::kTruncated;
    }
    if (bad || (tag >> 3) == 0) {
      return EgmDecodeStatus::kMalformed;
    }
    std::uint64_t len = 0;
    switch (tag & 7) {
      case 0:
        if (!egm_fast::read_varint(p, end, len, bad)) {
          return EgmDecodeStatus::kTruncated;
        }
        if (bad) {
          return EgmDecodeStatus::kMalformed;
        }
        break;
      case 1:
        if (end - p < 8) {
          return EgmDecodeStatus::kTruncated;
        }
        p += 8;
        break;
      case 2:
        if (!egm_fast::read_varint(p, end, len, bad)) {
          return EgmDecodeStatus::kTruncated;
        }
        if (bad) {
          return EgmDecodeStatus::kMalformed;
        }
        if (len > static_cast<std::uint64_t>(end - p)) {
          return EgmDecodeStatus::kTruncated;
        }
        p += len;
        break;
      case 5:
        if (end - p < 4) {
          return EgmDecodeStatus::kTruncated;
        }
        p += 4;
        break;
      default:
        return EgmDecodeStatus::kMalformed;  // groups (3, 4) are not in EGM; 6 and 7 do not exist
    }
  }
  return EgmDecodeStatus::kOk;
}

EgmCodec::EgmCodec(int expected_joints) : impl_(std::make_unique<Impl>()), expected_joints_(expected_joints) {
  // Protobuf's own error lines would flood stderr on a stream of bad packets (one line each); they
  // are counted instead (egm_protobuf_log_messages). Set once: the handler is process-wide.
  static std::once_flag silenced;
  std::call_once(silenced, [] { google::protobuf::SetLogHandler(&count_protobuf_log); });
  // Warm the messages once so their sub-messages and repeated fields exist before the first cycle
  // (protobuf decodes only what the hand-written reader leaves, so it is warmed directly).
  EgmRobotMessage r;
  r.feedback_joints_deg = JointVector::Zero(expected_joints);
  r.planned_joints_deg = JointVector::Zero(expected_joints);
  r.has_planned = true;
  unsigned char buf[1024];
  const std::size_t n = encode_robot(r, buf, sizeof(buf));
  (void)impl_->robot_in.ParsePartialFromArray(buf, static_cast<int>(n));
  EgmSensorMessage s;
  s.planned_joints_deg = JointVector::Zero(expected_joints);
  s.speed_ref_joints_deg_s = JointVector::Zero(expected_joints);
  const std::size_t m = encode_sensor(s, buf, sizeof(buf));
  (void)impl_->sensor_in.ParsePartialFromArray(buf, static_cast<int>(m));
  const std::size_t k = encode_path_corr(EgmPathCorrMessage{}, buf, sizeof(buf));
  EgmPathCorrMessage pback;
  (void)decode_path_corr(buf, k, pback);
}

EgmCodec::~EgmCodec() = default;

EgmDecodeStatus EgmCodec::decode_robot(const unsigned char* data, std::size_t size, EgmRobotMessage& out) noexcept {
  if (size == 0) {
    return EgmDecodeStatus::kEmpty;
  }
  if (egm_fast::decode_robot(data, size, expected_joints_, out)) {
    return EgmDecodeStatus::kOk;  // a well-formed message of the common shape (it checks the wire format)
  }
  const EgmDecodeStatus wire = scan_wire_format(data, size);
  if (wire != EgmDecodeStatus::kOk) {
    return wire;
  }
  if (!header_seqno_fits(data, size)) {
    return EgmDecodeStatus::kSequenceOutOfRange;
  }
  abb::egm::EgmRobot& m = impl_->robot_in;
  // ParsePartial + IsInitialized rather than Parse: the same verdict, without protobuf's error line.
  if (!m.ParsePartialFromArray(data, static_cast<int>(size))) {
    return EgmDecodeStatus::kMalformed;
  }
  if (!m.IsInitialized()) {
    return EgmDecodeStatus::kMissingRequired;  // a required field inside a sub-message is absent
  }
  if (!m.has_header() || !m.header().has_seqno()) {
    return EgmDecodeStatus::kMissingHeader;
  }
  if (!m.has_feedback() || !m.feedback().has_joints() ||
      !copy_joints(m.feedback().joints(), expected_joints_, out.feedback_joints_deg)) {
    return EgmDecodeStatus::kMissingJoints;
  }
  out.has_planned = m.has_planned() && m.planned().has_joints();
  if (out.has_planned) {
    if (!copy_joints(m.planned().joints(), expected_joints_, out.planned_joints_deg)) {
      return EgmDecodeStatus::kMissingJoints;
    }
  } else {
    out.planned_joints_deg.setZero(expected_joints_);
  }
  if (!out.feedback_joints_deg.allFinite() || !out.planned_joints_deg.allFinite()) {
    return EgmDecodeStatus::kNonFinite;
  }
  out.seqno = m.header().seqno();
  out.tm_ms = m.header().tm();
  out.motor_state = m.has_motorstate() ? static_cast<int>(m.motorstate().state()) : 0;
  out.mci_state = m.has_mcistate() ? static_cast<int>(m.mcistate().state()) : 0;
  out.rapid_exec_state = m.has_rapidexecstate() ? static_cast<int>(m.rapidexecstate().state()) : 0;
  out.mci_convergence_met = m.mciconvergencemet();
  return EgmDecodeStatus::kOk;
}

std::size_t EgmCodec::encode_sensor(const EgmSensorMessage& msg, unsigned char* out, std::size_t capacity) noexcept {
  if (!msg.planned_joints_deg.allFinite() || !msg.speed_ref_joints_deg_s.allFinite()) {
    return 0;
  }
  const std::size_t n = egm_fast::encode_sensor(msg, impl_->speed_ref_sent, out, capacity);
  impl_->speed_ref_sent = impl_->speed_ref_sent || msg.speed_ref_joints_deg_s.size() > 0;
  return n;
}

std::size_t EgmCodec::encode_robot(const EgmRobotMessage& msg, unsigned char* out, std::size_t capacity) noexcept {
  return egm_fast::encode_robot(msg, out, capacity);
}

bool EgmCodec::decode_sensor(const unsigned char* data, std::size_t size, EgmSensorMessage& out) noexcept {
  if (size == 0) {
    return false;
  }
  if (egm_fast::decode_sensor(data, size, expected_joints_, out)) {
    return true;
  }
  if (scan_wire_format(data, size) != EgmDecodeStatus::kOk) {
    return false;
  }
  abb::egm::EgmSensor& m = impl_->sensor_in;
  if (!m.ParsePartialFromArray(data, static_cast<int>(size)) || !m.IsInitialized() || !m.has_planned() ||
      !m.planned().has_joints()) {
    return false;
  }
  if (!copy_joints(m.planned().joints(), expected_joints_, out.planned_joints_deg)) {
    return false;
  }
  out.speed_ref_joints_deg_s.resize(0);
  if (m.has_speedref() && m.speedref().has_joints() && m.speedref().joints().joints_size() > 0 &&
      !copy_joints(m.speedref().joints(), expected_joints_, out.speed_ref_joints_deg_s)) {
    return false;
  }
  out.seqno = m.has_header() ? m.header().seqno() : 0;
  out.tm_ms = m.has_header() ? m.header().tm() : 0;
  return out.planned_joints_deg.allFinite() && out.speed_ref_joints_deg_s.allFinite();
}

std::size_t EgmCodec::encode_path_corr(const EgmPathCorrMessage& msg, unsigned char* out,
                                       std::size_t capacity) noexcept {
  if (!msg.pos_mm.allFinite()) {
    return 0;
  }
  abb::egm::EgmSensorPathCorr& m = impl_->path_out;
  m.mutable_header()->set_seqno(msg.seqno);
  m.mutable_header()->set_tm(msg.tm_ms);
  m.mutable_header()->set_mtype(abb::egm::EgmHeader::MSGTYPE_PATH_CORRECTION);
  m.mutable_pathcorr()->mutable_pos()->set_x(msg.pos_mm.x());
  m.mutable_pathcorr()->mutable_pos()->set_y(msg.pos_mm.y());
  m.mutable_pathcorr()->mutable_pos()->set_z(msg.pos_mm.z());
  m.mutable_pathcorr()->set_age(msg.age_ms);
  const std::size_t n = m.ByteSizeLong();
  if (n > capacity || !m.SerializeToArray(out, static_cast<int>(capacity))) {
    return 0;
  }
  return n;
}

bool EgmCodec::decode_path_corr(const unsigned char* data, std::size_t size, EgmPathCorrMessage& out) noexcept {
  if (size == 0 || scan_wire_format(data, size) != EgmDecodeStatus::kOk) {
    return false;
  }
  abb::egm::EgmSensorPathCorr& m = impl_->path_in;
  if (!m.ParsePartialFromArray(data, static_cast<int>(size)) || !m.IsInitialized() || !m.has_pathcorr()) {
    return false;  // pathCorr's pos and age are required: protobuf refuses a message without them
  }
  out.pos_mm = Vector3(m.pathcorr().pos().x(), m.pathcorr().pos().y(), m.pathcorr().pos().z());
  out.age_ms = m.pathcorr().age();
  out.seqno = m.has_header() ? m.header().seqno() : 0;
  out.tm_ms = m.has_header() ? m.header().tm() : 0;
  return out.pos_mm.allFinite();
}

}  // namespace deflex
