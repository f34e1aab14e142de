// The order of a sender's numbered datagrams, case by case as the links meet them: the next number, a
// duplicate, a late one, a stray far ahead (refused, and the real sequence goes on untouched), a
// genuine jump (taken once the datagrams after it continue it), a restart from a small number, the
// 32-bit wrap, 64-bit IPOC time stamps, and the rules' own validation.
#include <gtest/gtest.h>

#include "deflex/text/errors.hpp"
#include "deflex/transport/sequence_tracker.hpp"

namespace deflex {
namespace {

using V = SequenceVerdict;

TEST(SequenceTracker, NextDuplicateAndLateNumbers) {
  SequenceTracker t;
  EXPECT_EQ(t.observe(10), V::kFirst);
  EXPECT_EQ(t.observe(11), V::kNext);
  EXPECT_EQ(t.observe(13), V::kNext);  // 12 was lost: still the next one taken
  EXPECT_EQ(t.observe(13), V::kDuplicate);
  EXPECT_EQ(t.observe(12), V::kOutOfOrder);
  EXPECT_EQ(t.observe(14), V::kNext);
  EXPECT_EQ(t.last(), 14u);
}

TEST(SequenceTracker, AStrayFarAheadDoesNotCaptureTheSequence) {
  SequenceTracker t;  // EGM's rules: 250 ahead at most, 3 to confirm a jump
  for (std::uint64_t s = 1; s <= 100; ++s) t.observe(s);
  EXPECT_EQ(t.observe(100100), V::kFarAhead);
  // The real sender's next packets are all taken (before, the stray's number became the running one
  // and the next 93 real packets were refused as out of order).
  for (std::uint64_t s = 101; s <= 200; ++s) EXPECT_EQ(t.observe(s), V::kNext) << s;
  // Two strays in a row, interrupted by the real sender, still capture nothing.
  EXPECT_EQ(t.observe(500000), V::kFarAhead);
  EXPECT_EQ(t.observe(500001), V::kFarAhead);
  EXPECT_EQ(t.observe(201), V::kNext);
  EXPECT_EQ(t.observe(500002), V::kFarAhead);
  EXPECT_EQ(t.last(), 201u);
}

TEST(SequenceTracker, AGenuineJumpIsTakenOnceThreeInARowContinueIt) {
  SequenceTracker t;
  for (std::uint64_t s = 1; s <= 10; ++s) t.observe(s);
  EXPECT_EQ(t.observe(5000), V::kFarAhead);
  EXPECT_EQ(t.observe(5001), V::kFarAhead);
  EXPECT_EQ(t.observe(5002), V::kRestart);
  EXPECT_EQ(t.observe(5003), V::kNext);
  // The same for a big jump back (a sender restarted at an arbitrary number).
  EXPECT_EQ(t.observe(700), V::kOutOfOrder);
  EXPECT_EQ(t.observe(701), V::kOutOfOrder);
  EXPECT_EQ(t.observe(702), V::kRestart);
  EXPECT_EQ(t.last(), 702u);
}

TEST(SequenceTracker, AJumpBackToASmallNumberIsARestartAtOnce) {
  SequenceTracker t;
  t.observe(500);
  t.observe(501);
  EXPECT_EQ(t.observe(1), V::kRestart);
  EXPECT_EQ(t.observe(2), V::kNext);
  SequenceRules no_small;  // RSI: IPOC never restarts from a small number
  no_small.restart_max = 0;
  SequenceTracker r(no_small);
  r.observe(500);
  EXPECT_EQ(r.observe(1), V::kOutOfOrder);
}

TEST(SequenceTracker, ThirtyTwoBitNumbersWrapAndSixtyFourBitOnesDoNot) {
  SequenceTracker t;
  t.observe(0xFFFFFFFEu);
  EXPECT_EQ(t.observe(0xFFFFFFFFu), V::kNext);
  EXPECT_EQ(t.observe(0), V::kNext);
  EXPECT_EQ(t.observe(1), V::kNext);

  SequenceRules ipoc;
  ipoc.bits = 64;
  ipoc.max_ahead = 1000;  // ms of IPOC
  ipoc.restart_max = 0;
  SequenceTracker i(ipoc);
  const std::uint64_t start = 0x1'0000'0000ULL - 8;  // across 2^32: no wrap, no truncation
  i.observe(start);
  EXPECT_EQ(i.observe(start + 4), V::kNext);
  EXPECT_EQ(i.observe(start + 8), V::kNext);
  EXPECT_EQ(i.observe(start + 12), V::kNext);
  EXPECT_EQ(i.last(), 0x1'0000'0004ULL);
  EXPECT_EQ(i.observe(4), V::kOutOfOrder);  // what a truncation to 32 bits would have looked like
  EXPECT_EQ(i.observe(start + 12 + 5000), V::kFarAhead);
}

TEST(SequenceTracker, A64BitCounterThatWrapsAt32BitsGoesOnAcrossTheWrap) {
  // RSI's IPOC: the drivers read it as 64 bits; a controller counting in 32 wraps at 2^32 ms.
  SequenceRules ipoc;
  ipoc.bits = 64;
  ipoc.max_ahead = 1000;
  ipoc.restart_max = 0;
  ipoc.wraps_at_32 = true;
  SequenceTracker i(ipoc);
  i.observe(0xFFFF'FFF8ULL);
  EXPECT_EQ(i.observe(0xFFFF'FFFCULL), V::kNext);
  EXPECT_EQ(i.observe(0), V::kNext);  // across the wrap
  EXPECT_EQ(i.observe(4), V::kNext);
  EXPECT_EQ(i.observe(0xFFFF'FFFCULL), V::kOutOfOrder);  // a late one from before the wrap
  EXPECT_EQ(SequenceTracker::distance(ipoc, 0xFFFF'FFFCULL, 4), 8);
  EXPECT_EQ(SequenceTracker::distance(ipoc, 4, 0xFFFF'FFFCULL), -8);
  // A 64-bit counter past 2^32 is plain 64-bit arithmetic: nothing wraps.
  EXPECT_EQ(SequenceTracker::distance(ipoc, 0x1'0000'0004ULL, 4), -static_cast<std::int64_t>(0x1'0000'0000ULL));
  // Far apart within 32 bits, no wrap is nearer: the plain difference.
  EXPECT_EQ(SequenceTracker::distance(ipoc, 1000, 0x8000'0000ULL), 0x8000'0000LL - 1000);
}

TEST(SequenceTracker, RulesOutOfRangeAreRefused) {
  SequenceRules r;
  r.bits = 16;
  EXPECT_THROW(r.validate(), InputError);
  r = SequenceRules{};
  r.max_ahead = 0;
  EXPECT_THROW(r.validate(), InputError);
  r = SequenceRules{};
  r.confirm = 0;
  EXPECT_THROW(r.validate(), InputError);
  EXPECT_NO_THROW(SequenceRules{}.validate());
}

}  // namespace
}  // namespace deflex
