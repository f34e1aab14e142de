// The hand-written EGM joint-mode coder (wire/detail/egm_fast.hpp) against protobuf's generated
// classes, the independent reference: its encoders write protobuf's bytes for the same messages (a
// reused message, as the codec kept one), and whatever its decoders take, protobuf parses to the same
// values; on random messages, on every shape a controller may add, and on mutated bytes.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "deflex/wire/detail/egm_fast.hpp"
#include "deflex/wire/egm_codec.hpp"
#include "egm.pb.h"

namespace deflex {
namespace {

using Bytes = std::vector<unsigned char>;

JointVector random_joints(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> deg(-400.0, 400.0);
  JointVector q(n);
  for (int i = 0; i < n; ++i) q[i] = deg(rng);
  return q;
}

std::uint32_t random_u32(std::mt19937_64& rng) {
  // Small and large alike: every varint length from 1 to 5 bytes.
  const int bits = static_cast<int>(rng() % 33);
  return bits == 0 ? 0U : static_cast<std::uint32_t>(rng() >> (64 - bits));
}

template <class Message>
void set_joints(const JointVector& q, Message* j) {
  j->clear_joints();
  for (int i = 0; i < q.size(); ++i) j->add_joints(q[i]);
}

Bytes bytes_of(const std::string& s) { return Bytes(s.begin(), s.end()); }

// EgmRobot as the codec built it with protobuf (one message, reused).
Bytes protobuf_robot(abb::egm::EgmRobot& m, const EgmRobotMessage& msg) {
  m.mutable_header()->set_seqno(msg.seqno);
  m.mutable_header()->set_tm(msg.tm_ms);
  m.mutable_header()->set_mtype(abb::egm::EgmHeader::MSGTYPE_DATA);
  set_joints(msg.feedback_joints_deg, m.mutable_feedback()->mutable_joints());
  if (msg.has_planned) {
    set_joints(msg.planned_joints_deg, m.mutable_planned()->mutable_joints());
  } else {
    m.clear_planned();
  }
  m.mutable_motorstate()->set_state(msg.motor_state == 2 ? abb::egm::EgmMotorState::MOTORS_OFF
                                                         : abb::egm::EgmMotorState::MOTORS_ON);
  m.mutable_mcistate()->set_state(msg.mci_state == 1   ? abb::egm::EgmMCIState::MCI_ERROR
                                  : msg.mci_state == 2 ? abb::egm::EgmMCIState::MCI_STOPPED
                                                       : abb::egm::EgmMCIState::MCI_RUNNING);
  m.mutable_rapidexecstate()->set_state(msg.rapid_exec_state == 1 ? abb::egm::EgmRapidCtrlExecState::RAPID_STOPPED
                                                                  : abb::egm::EgmRapidCtrlExecState::RAPID_RUNNING);
  m.set_mciconvergencemet(msg.mci_convergence_met);
  return bytes_of(m.SerializeAsString());
}

// EgmSensor as the codec built it with protobuf (one message, reused).
Bytes protobuf_sensor(abb::egm::EgmSensor& m, const EgmSensorMessage& msg) {
  m.mutable_header()->set_seqno(msg.seqno);
  m.mutable_header()->set_tm(msg.tm_ms);
  m.mutable_header()->set_mtype(abb::egm::EgmHeader::MSGTYPE_CORRECTION);
  set_joints(msg.planned_joints_deg, m.mutable_planned()->mutable_joints());
  if (msg.speed_ref_joints_deg_s.size() > 0) {
    set_joints(msg.speed_ref_joints_deg_s, m.mutable_speedref()->mutable_joints());
  } else if (m.has_speedref()) {
    m.mutable_speedref()->mutable_joints()->clear_joints();
  }
  return bytes_of(m.SerializeAsString());
}

EgmRobotMessage random_robot(std::mt19937_64& rng, int n) {
  EgmRobotMessage msg;
  msg.seqno = random_u32(rng);
  msg.tm_ms = random_u32(rng);
  msg.feedback_joints_deg = random_joints(rng, n);
  msg.has_planned = rng() % 3 != 0;
  msg.planned_joints_deg = random_joints(rng, n);
  msg.motor_state = static_cast<int>(rng() % 3);
  msg.mci_state = static_cast<int>(rng() % 4);
  msg.rapid_exec_state = static_cast<int>(rng() % 3);
  msg.mci_convergence_met = rng() % 2 == 0;
  return msg;
}

TEST(EgmFast, EncodersWriteProtobufsBytesForTheSameMessages) {
  std::mt19937_64 rng(20261129);
  EgmCodec codec(6);
  abb::egm::EgmRobot robot;
  abb::egm::EgmSensor sensor;
  // The codec warmed its protobuf message with a speed reference when it was made, so the reused
  // message sent an empty speedRef.joints from its first answer without one: the same here.
  EgmSensorMessage warm;
  warm.planned_joints_deg = JointVector::Zero(6);
  warm.speed_ref_joints_deg_s = JointVector::Zero(6);
  (void)protobuf_sensor(sensor, warm);
  unsigned char out[2048];
  for (int k = 0; k < 3000; ++k) {
    const int n = static_cast<int>(rng() % 8);  // 0..7 joints: every length the vector holds
    const EgmRobotMessage r = random_robot(rng, n);
    const Bytes expected_robot = protobuf_robot(robot, r);
    const std::size_t rn = egm_fast::encode_robot(r, out, sizeof(out));
    ASSERT_EQ(Bytes(out, out + rn), expected_robot) << "robot message " << k;
    EgmSensorMessage s;
    s.seqno = random_u32(rng);
    s.tm_ms = random_u32(rng);
    s.planned_joints_deg = random_joints(rng, 6);
    if (k > 0 && rng() % 2 == 0) s.speed_ref_joints_deg_s = random_joints(rng, 6);  // the first without
    // Through the codec: it keeps the reused message's memory of a speed reference sent.
    const Bytes expected_sensor = protobuf_sensor(sensor, s);
    const std::size_t sn = codec.encode_sensor(s, out, sizeof(out));
    ASSERT_EQ(Bytes(out, out + sn), expected_sensor) << "sensor message " << k;
    // One byte short of the message: nothing written, as protobuf's size check refused it.
    ASSERT_EQ(egm_fast::encode_robot(r, out, expected_robot.size() - 1), 0u);
    ASSERT_EQ(codec.encode_sensor(s, out, expected_sensor.size() - 1), 0u);
  }
}

// What protobuf reads from bytes the hand-written reader took, field by field.
void expect_protobuf_agrees(const Bytes& b, const EgmRobotMessage& fast, int expected) {
  abb::egm::EgmRobot m;
  ASSERT_TRUE(m.ParseFromArray(b.data(), static_cast<int>(b.size())));  // parsed and initialised
  ASSERT_TRUE(m.has_header() && m.header().has_seqno());
  EXPECT_EQ(fast.seqno, m.header().seqno());
  EXPECT_EQ(fast.tm_ms, m.header().tm());
  ASSERT_EQ(m.feedback().joints().joints_size(), expected);
  for (int i = 0; i < expected; ++i) EXPECT_EQ(fast.feedback_joints_deg[i], m.feedback().joints().joints(i));
  ASSERT_EQ(fast.has_planned, m.has_planned() && m.planned().has_joints());
  for (int i = 0; i < expected; ++i) {
    EXPECT_EQ(fast.planned_joints_deg[i], fast.has_planned ? m.planned().joints().joints(i) : 0.0);
  }
  EXPECT_EQ(fast.motor_state, m.has_motorstate() ? static_cast<int>(m.motorstate().state()) : 0);
  EXPECT_EQ(fast.mci_state, m.has_mcistate() ? static_cast<int>(m.mcistate().state()) : 0);
  EXPECT_EQ(fast.rapid_exec_state, m.has_rapidexecstate() ? static_cast<int>(m.rapidexecstate().state()) : 0);
  EXPECT_EQ(fast.mci_convergence_met, m.mciconvergencemet());
}

// A controller's EgmRobot with what a real one may add (the Cartesian pose, the time, test signals,
// the utilisation rate ...), packed joints, or a field twice: the hand-written reader takes only the
// common shape and leaves the rest to protobuf.
Bytes varied_robot(std::mt19937_64& rng, const EgmRobotMessage& r, bool& common) {
  abb::egm::EgmRobot m;
  Bytes b = protobuf_robot(m, r);
  common = true;
  switch (rng() % 6) {
    case 0:
      m.mutable_feedback()->mutable_cartesian()->mutable_pos()->set_x(1.0);
      m.mutable_feedback()->mutable_cartesian()->mutable_pos()->set_y(2.0);
      m.mutable_feedback()->mutable_cartesian()->mutable_pos()->set_z(3.0);
      common = false;
      break;
    case 1:
      m.set_utilizationrate(42.0);
      common = false;
      break;
    case 2:
      m.mutable_testsignals()->add_signals(0.5);
      common = false;
      break;
    case 3: {  // the header again: protobuf merges it, the reader declines
      abb::egm::EgmRobot h;
      h.mutable_header()->set_tm(7);
      const std::string extra = h.SerializeAsString();
      b.insert(b.end(), extra.begin(), extra.end());
      common = false;
      return b;
    }
    default:
      return b;
  }
  return bytes_of(m.SerializeAsString());
}

TEST(EgmFast, WhatTheRobotReaderTakesProtobufParsesTheSame) {
  std::mt19937_64 rng(7);
  int taken = 0, left = 0;
  for (int k = 0; k < 3000; ++k) {
    const EgmRobotMessage r = random_robot(rng, 6);
    bool common = false;
    const Bytes b = varied_robot(rng, r, common);
    EgmRobotMessage fast;
    const bool took = egm_fast::decode_robot(b.data(), b.size(), 6, fast);
    ASSERT_EQ(took, common) << "message " << k;  // the codec's own messages are all taken
    if (took) {
      expect_protobuf_agrees(b, fast, 6);
      ++taken;
    } else {
      ++left;
    }
    // Expecting another joint count: never taken (protobuf's path then says missing joints).
    EgmRobotMessage other;
    EXPECT_FALSE(egm_fast::decode_robot(b.data(), b.size(), 7, other));
  }
  EXPECT_GT(taken, 800);  // a third of them are the common shape
  EXPECT_GT(left, 1600);
}

TEST(EgmFast, MutatedBytesAreEitherLeftToProtobufOrReadAsProtobufReadsThem) {
  std::mt19937_64 rng(11);
  int taken = 0;
  for (int k = 0; k < 20000; ++k) {
    EgmRobotMessage r = random_robot(rng, 6);
    abb::egm::EgmRobot m;
    Bytes b = protobuf_robot(m, r);
    // Flip, drop, insert or cut bytes: one to three times.
    const int edits = 1 + static_cast<int>(rng() % 3);
    for (int e = 0; e < edits && !b.empty(); ++e) {
      const std::size_t at = rng() % b.size();
      switch (rng() % 4) {
        case 0:
          b[at] = static_cast<unsigned char>(rng());
          break;
        case 1:
          b.erase(b.begin() + static_cast<long>(at));
          break;
        case 2:
          b.insert(b.begin() + static_cast<long>(at), static_cast<unsigned char>(rng()));
          break;
        default:
          b.resize(at);
          break;
      }
    }
    EgmRobotMessage fast;
    if (egm_fast::decode_robot(b.data(), b.size(), 6, fast)) {
      ++taken;
      expect_protobuf_agrees(b, fast, 6);
      ASSERT_TRUE(fast.feedback_joints_deg.allFinite() && fast.planned_joints_deg.allFinite());
    }
    EgmSensorMessage s;
    if (egm_fast::decode_sensor(b.data(), b.size(), 6, s)) {
      abb::egm::EgmSensor sm;
      ASSERT_TRUE(sm.ParseFromArray(b.data(), static_cast<int>(b.size())));
      ASSERT_EQ(sm.planned().joints().joints_size(), 6);
    }
  }
  EXPECT_GT(taken, 0);  // some edits (a flipped bit of a double) leave a message of the common shape
}

TEST(EgmFast, WhatTheSensorReaderTakesProtobufParsesTheSame) {
  std::mt19937_64 rng(3);
  abb::egm::EgmSensor reused;
  for (int k = 0; k < 3000; ++k) {
    EgmSensorMessage s;
    s.seqno = random_u32(rng);
    s.tm_ms = random_u32(rng);
    s.planned_joints_deg = random_joints(rng, 6);
    if (rng() % 2 == 0) s.speed_ref_joints_deg_s = random_joints(rng, 6);
    if (rng() % 5 == 0) s.planned_joints_deg[static_cast<int>(rng() % 6)] = std::numeric_limits<double>::quiet_NaN();
    Bytes b = protobuf_sensor(reused, s);
    EgmSensorMessage fast;
    const bool took = egm_fast::decode_sensor(b.data(), b.size(), 6, fast);
    ASSERT_EQ(took, s.planned_joints_deg.allFinite()) << k;  // a NaN is protobuf's path to refuse
    if (!took) continue;
    abb::egm::EgmSensor m;
    ASSERT_TRUE(m.ParseFromArray(b.data(), static_cast<int>(b.size())));
    EXPECT_EQ(fast.seqno, m.header().seqno());
    EXPECT_EQ(fast.tm_ms, m.header().tm());
    for (int i = 0; i < 6; ++i) EXPECT_EQ(fast.planned_joints_deg[i], m.planned().joints().joints(i));
    ASSERT_EQ(fast.speed_ref_joints_deg_s.size(), m.speedref().joints().joints_size());
    for (int i = 0; i < fast.speed_ref_joints_deg_s.size(); ++i) {
      EXPECT_EQ(fast.speed_ref_joints_deg_s[i], m.speedref().joints().joints(i));
    }
  }
}

}  // namespace
}  // namespace deflex
