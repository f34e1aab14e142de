// EGM's joint-mode messages coded by hand (see detail/egm_fast.hpp).
#include "deflex/wire/detail/egm_fast.hpp"

#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <utility>

#include "deflex/wire/detail/byte_order.hpp"

namespace deflex::egm_fast {
namespace {

// Protobuf's wire types and the tags of the fields written and read here (field << 3 | type).
constexpr std::uint64_t kVarint = 0, kFixed64 = 1, kLength = 2;
constexpr std::uint64_t tag(std::uint64_t field, std::uint64_t type) { return field << 3 | type; }

// The enum values EgmHeader.MessageType, EgmMotorState, EgmMCIState and EgmRapidCtrlExecState know;
// any other leaves the field unset in protobuf (an unknown enum value), which is protobuf's to judge.
constexpr std::uint64_t kMessageTypes = 5, kMotorStates = 3, kMciStates = 4, kRapidStates = 3;

// Protobuf's doubles are little-endian: copied as they are on a little-endian host.
std::uint64_t load_le64(const unsigned char* p) {
  if constexpr (std::endian::native == std::endian::little) {
    std::uint64_t v = 0;
    std::memcpy(&v, p, 8);
    return v;
  } else {
    return wire_bytes::load<std::uint64_t>(wire_bytes::Order::kLittle, p);
  }
}
void store_le64(std::uint64_t v, unsigned char* p) {
  if constexpr (std::endian::native == std::endian::little) {
    std::memcpy(p, &v, 8);
  } else {
    wire_bytes::store(wire_bytes::Order::kLittle, v, p);
  }
}

// ---- writing ----

std::size_t varint_size(std::uint64_t v) {
  std::size_t n = 1;
  for (; v >= 0x80; v >>= 7) ++n;
  return n;
}

struct Writer {
  unsigned char* p;
  void varint(std::uint64_t v) {
    for (; v >= 0x80; v >>= 7) *p++ = static_cast<unsigned char>(v | 0x80);
    *p++ = static_cast<unsigned char>(v);
  }
  void fixed64(double v) {
    store_le64(std::bit_cast<std::uint64_t>(v), p);
    p += 8;
  }
};

// An EgmJoints message: the joints one tagged double each (proto2 repeated fields are not packed).
std::size_t joints_size(const JointVector& q) { return 9 * static_cast<std::size_t>(q.size()); }
void write_joints(Writer& w, const JointVector& q) {
  for (int i = 0; i < q.size(); ++i) {
    w.varint(tag(1, kFixed64));
    w.fixed64(q[i]);
  }
}
// A message whose only field, 1, is an EgmJoints (EgmFeedBack, EgmPlanned, EgmSpeedRef as sent here).
std::size_t holder_size(const JointVector& q) { return 1 + varint_size(joints_size(q)) + joints_size(q); }
void write_holder(Writer& w, std::uint64_t field, const JointVector& q) {
  w.varint(tag(field, kLength));
  w.varint(holder_size(q));
  w.varint(tag(1, kLength));
  w.varint(joints_size(q));
  write_joints(w, q);
}

std::size_t header_size(std::uint32_t seqno, std::uint32_t tm) { return 4 + varint_size(seqno) + varint_size(tm); }
void write_header(Writer& w, std::uint32_t seqno, std::uint32_t tm, std::uint64_t type) {
  w.varint(tag(1, kLength));
  w.varint(header_size(seqno, tm));
  w.varint(tag(1, kVarint));
  w.varint(seqno);
  w.varint(tag(2, kVarint));
  w.varint(tm);
  w.varint(tag(3, kVarint));
  w.varint(type);
}

// A state message (its one field, 1, a small enum), as field `field`.
void write_state(Writer& w, std::uint64_t field, std::uint64_t state) {
  w.varint(tag(field, kLength));
  w.varint(2);
  w.varint(tag(1, kVarint));
  w.varint(state);
}

// ---- reading ----

struct Cursor {
  const unsigned char* p;
  const unsigned char* end;
  [[nodiscard]] bool done() const { return p >= end; }
  // A varint of at most 10 bytes that fits 64 bits; false when truncated or wider.
  bool varint(std::uint64_t& v) {
    bool bad = false;
    return read_varint(p, end, v, bad) && !bad;
  }
  // The body of a length-delimited field whose tag was read.
  bool body(Cursor& out) {
    std::uint64_t len = 0;
    if (!varint(len) || len > static_cast<std::uint64_t>(end - p)) return false;
    out = Cursor{p, p + len};
    p += len;
    return true;
  }
};

struct Joints {
  bool present = false;
  int n = 0;
  std::array<double, kMaxJoints> q{};
};

// An EgmJoints body, unpacked doubles only (packed ones are protobuf's).
bool read_joints(Cursor c, Joints& j) {
  j.present = true;
  while (!c.done()) {
    std::uint64_t t = 0;
    if (!c.varint(t) || t != tag(1, kFixed64) || c.end - c.p < 8 || j.n >= kMaxJoints) return false;
    j.q[static_cast<std::size_t>(j.n++)] = std::bit_cast<double>(load_le64(c.p));
    c.p += 8;
  }
  return true;
}

// A body whose only field is 1, an EgmJoints, at most once.
bool read_holder(Cursor c, Joints& j) {
  while (!c.done()) {
    std::uint64_t t = 0;
    Cursor inner{};
    if (!c.varint(t) || t != tag(1, kLength) || j.present || !c.body(inner) || !read_joints(inner, j)) return false;
  }
  return true;
}

struct Header {
  bool has_seqno = false, has_tm = false, has_type = false;
  std::uint64_t seqno = 0, tm = 0;
};

bool read_header(Cursor c, Header& h) {
  while (!c.done()) {
    std::uint64_t t = 0, v = 0;
    if (!c.varint(t) || !c.varint(v)) return false;
    bool* seen = nullptr;
    if (t == tag(1, kVarint)) {
      seen = &h.has_seqno;
      h.seqno = v;
    } else if (t == tag(2, kVarint)) {
      seen = &h.has_tm;
      h.tm = v;
    } else if (t == tag(3, kVarint) && v < kMessageTypes) {
      seen = &h.has_type;
    } else {
      return false;
    }
    if (*seen || v > 0xFFFFFFFFULL) return false;
    *seen = true;
  }
  return true;
}

// A state message's body: its required field 1, once, a value of the enum.
bool read_state(Cursor c, std::uint64_t values, int& state) {
  std::uint64_t t = 0, v = 0;
  if (!c.varint(t) || t != tag(1, kVarint) || !c.varint(v) || v >= values || !c.done()) return false;
  state = static_cast<int>(v);
  return true;
}

bool whole(const Joints& j, int expected) {
  if (j.n != expected) return false;
  for (int i = 0; i < j.n; ++i) {
    if (!std::isfinite(j.q[static_cast<std::size_t>(i)])) return false;
  }
  return true;
}

void copy(const Joints& j, JointVector& out) {
  out.resize(j.n);
  for (int i = 0; i < j.n; ++i) out[i] = j.q[static_cast<std::size_t>(i)];
}

// What an EgmRobot of the common shape holds, each field at most once.
struct RobotFields {
  Header header;
  bool has_header = false, has_feedback = false, has_planned = false, has_convergence = false;
  Joints feedback, planned;
  int motor = 0, mci = 0, rapid = 0;
  bool has_motor = false, has_mci = false, has_rapid = false;
  std::uint64_t convergence = 0;
};

// One top-level field of an EgmRobot; false for any field, type or repeat this reader does not take.
bool read_robot_field(Cursor& c, std::uint64_t t, RobotFields& r) {
  if (t == tag(6, kVarint)) {
    if (r.has_convergence) return false;
    r.has_convergence = true;
    return c.varint(r.convergence);
  }
  Cursor body{};
  if ((t & 7) != kLength || !c.body(body)) return false;
  const auto once = [](bool& seen) { return !std::exchange(seen, true); };
  switch (t >> 3) {
    case 1:
      return once(r.has_header) && read_header(body, r.header);
    case 2:
      return once(r.has_feedback) && read_holder(body, r.feedback);
    case 3:
      return once(r.has_planned) && read_holder(body, r.planned);
    case 4:
      return once(r.has_motor) && read_state(body, kMotorStates, r.motor);
    case 5:
      return once(r.has_mci) && read_state(body, kMciStates, r.mci);
    case 8:
      return once(r.has_rapid) && read_state(body, kRapidStates, r.rapid);
    default:
      return false;
  }
}

}  // namespace

std::size_t encode_robot(const EgmRobotMessage& msg, unsigned char* out, std::size_t capacity) noexcept {
  const std::size_t header = header_size(msg.seqno, msg.tm_ms);
  std::size_t n = 1 + varint_size(header) + header;
  n += 1 + varint_size(holder_size(msg.feedback_joints_deg)) + holder_size(msg.feedback_joints_deg);
  if (msg.has_planned) {
    n += 1 + varint_size(holder_size(msg.planned_joints_deg)) + holder_size(msg.planned_joints_deg);
  }
  n += 4 + 4 + 2 + 4;  // motor and MCI state, the convergence flag, RAPID's state
  if (n > capacity) return 0;
  Writer w{out};
  write_header(w, msg.seqno, msg.tm_ms, 2);  // MSGTYPE_DATA
  write_holder(w, 2, msg.feedback_joints_deg);
  if (msg.has_planned) write_holder(w, 3, msg.planned_joints_deg);
  write_state(w, 4, msg.motor_state == 2 ? 2 : 1);                           // MOTORS_OFF : MOTORS_ON
  write_state(w, 5, msg.mci_state == 1 ? 1 : (msg.mci_state == 2 ? 2 : 3));  // ERROR, STOPPED, RUNNING
  w.varint(tag(6, kVarint));
  w.varint(msg.mci_convergence_met ? 1 : 0);
  write_state(w, 8, msg.rapid_exec_state == 1 ? 1 : 2);  // RAPID_STOPPED : RAPID_RUNNING
  return n;
}

std::size_t encode_sensor(const EgmSensorMessage& msg, bool empty_speed_ref, unsigned char* out,
                          std::size_t capacity) noexcept {
  const std::size_t header = header_size(msg.seqno, msg.tm_ms);
  std::size_t n = 1 + varint_size(header) + header;
  n += 1 + varint_size(holder_size(msg.planned_joints_deg)) + holder_size(msg.planned_joints_deg);
  const bool speed_ref = msg.speed_ref_joints_deg_s.size() > 0;
  if (speed_ref) {
    n += 1 + varint_size(holder_size(msg.speed_ref_joints_deg_s)) + holder_size(msg.speed_ref_joints_deg_s);
  } else if (empty_speed_ref) {
    n += 4;  // speedRef { joints {} }
  }
  if (n > capacity) return 0;
  Writer w{out};
  write_header(w, msg.seqno, msg.tm_ms, 3);  // MSGTYPE_CORRECTION
  write_holder(w, 2, msg.planned_joints_deg);
  if (speed_ref) {
    write_holder(w, 3, msg.speed_ref_joints_deg_s);
  } else if (empty_speed_ref) {
    write_holder(w, 3, JointVector());
  }
  return n;
}

bool decode_robot(const unsigned char* data, std::size_t size, int expected_joints, EgmRobotMessage& out) noexcept {
  Cursor c{data, data + size};
  RobotFields r;
  while (!c.done()) {
    std::uint64_t t = 0;
    if (!c.varint(t) || !read_robot_field(c, t, r)) return false;
  }
  // What decode_robot accepts, and nothing it would refuse or read otherwise: the header's sequence
  // number, the whole feedback, the planned joints whole when there, every state it holds.
  if (!r.has_header || !r.header.has_seqno || !whole(r.feedback, expected_joints)) return false;
  if (r.planned.present && !whole(r.planned, expected_joints)) return false;
  out.seqno = static_cast<std::uint32_t>(r.header.seqno);
  out.tm_ms = static_cast<std::uint32_t>(r.header.tm);
  copy(r.feedback, out.feedback_joints_deg);
  out.has_planned = r.planned.present;
  if (out.has_planned) {
    copy(r.planned, out.planned_joints_deg);
  } else {
    out.planned_joints_deg.setZero(expected_joints);
  }
  out.motor_state = r.motor;
  out.mci_state = r.mci;
  out.rapid_exec_state = r.rapid;
  out.mci_convergence_met = r.convergence != 0;
  return true;
}

bool decode_sensor(const unsigned char* data, std::size_t size, int expected_joints, EgmSensorMessage& out) noexcept {
  Cursor c{data, data + size};
  Header header;
  Joints planned, speed_ref;
  bool has_header = false, has_planned = false, has_speed_ref = false;
  while (!c.done()) {
    std::uint64_t t = 0;
    Cursor body{};
    if (!c.varint(t) || (t & 7) != kLength || !c.body(body)) return false;
    bool ok = false;
    if (t == tag(1, kLength)) {
      ok = !std::exchange(has_header, true) && read_header(body, header);
    } else if (t == tag(2, kLength)) {
      ok = !std::exchange(has_planned, true) && read_holder(body, planned);
    } else if (t == tag(3, kLength)) {
      ok = !std::exchange(has_speed_ref, true) && read_holder(body, speed_ref);
    }
    if (!ok) return false;
  }
  if (!planned.present || !whole(planned, expected_joints)) return false;
  if (speed_ref.n > 0 && !whole(speed_ref, expected_joints)) return false;
  copy(planned, out.planned_joints_deg);
  copy(speed_ref, out.speed_ref_joints_deg_s);
  out.seqno = static_cast<std::uint32_t>(header.seqno);
  out.tm_ms = static_cast<std::uint32_t>(header.tm);
  return true;
}

}  // namespace deflex::egm_fast
