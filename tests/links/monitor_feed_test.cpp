// The live monitor's feed: what a browser polling /data?since=N gets (every row once, in order, the
// window kept, NaN as null, text escaped, long answers in parts), the late answers counted with the
// summary's meaning, the status timeline's events, and a reader on another thread while the writer
// adds rows (every row once, in order: the lock-free publication). Parsed with nlohmann-json as the
// page's JSON.parse would; expected values built by hand from the rows given.
#include "deflex/runtime/monitor_feed.hpp"

#include <atomic>
#include <cmath>
#include <thread>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

namespace deflex::runtime {
namespace {

MonitorRow row_at(double t, double fz) {
  MonitorRow r;
  r.t_s = t;
  r.sequence = static_cast<std::uint64_t>(t * 250);
  r.wrench[2] = fz;
  r.dtheta_deg[1] = 0.01 * t;
  r.late = static_cast<std::uint64_t>(t);
  return r;
}

TEST(MonitorFeed, EveryRowOnceInOrderWithinTheWindow) {
  MonitorSetup setup;
  setup.link = "egm-\"joint\"";
  setup.joints = 6;
  setup.joint_bound_deg = 0.5;
  setup.window_s = 2.0;
  MonitorFeed feed(setup);
  for (int k = 0; k < 250; ++k) feed.add(row_at(k * 0.004, -400.0 + k));
  feed.flush();
  auto doc = nlohmann::json::parse(feed.json(0));
  EXPECT_EQ(doc["link"], "egm-\"joint\"");
  EXPECT_EQ(doc["next"], 250);
  EXPECT_EQ(doc["more"], false);
  ASSERT_EQ(doc["rows"]["t"].size(), 250u);
  EXPECT_DOUBLE_EQ(doc["rows"]["fz"][10].get<double>(), -390.0);
  EXPECT_NEAR(doc["rows"]["d2"][100].get<double>(), 0.01 * 0.4, 1e-9);
  // A poll from row 250 gets only what came since.
  for (int k = 250; k < 260; ++k) feed.add(row_at(k * 0.004, 0.0));
  feed.flush();
  doc = nlohmann::json::parse(feed.json(250));
  ASSERT_EQ(doc["rows"]["t"].size(), 10u);
  EXPECT_NEAR(doc["rows"]["t"][0].get<double>(), 1.0, 1e-12);
  // Rows older than the window are gone (to the row: 2 s at 4 ms is 501 rows with both ends); a late
  // browser gets the window and where it begins.
  for (int k = 260; k < 1000; ++k) feed.add(row_at(k * 0.004, 0.0));
  feed.flush();
  doc = nlohmann::json::parse(feed.json(0));
  EXPECT_EQ(doc["next"], 1000);
  EXPECT_EQ(doc["first"], 1000 - 501);
  ASSERT_EQ(doc["rows"]["t"].size(), 501u);
  EXPECT_NEAR(doc["rows"]["t"][0].get<double>(), 499 * 0.004, 1e-12);
  // NaN (a value the cycle did not have) is null, and the state's text is escaped.
  feed.add(row_at(4.0, std::nan("")));
  feed.set_state("ended", "controller-silent: no \"usable\" message\n");
  doc = nlohmann::json::parse(feed.json(1000));
  EXPECT_TRUE(doc["rows"]["fz"][0].is_null());
  EXPECT_EQ(doc["state"], "ended");
  EXPECT_EQ(doc["stop_reason"], "controller-silent: no \"usable\" message");
}

TEST(MonitorFeed, ARecordedLogKeepsEverythingAndIsAnsweredInParts) {
  MonitorSetup setup;
  setup.recorded = true;
  setup.window_s = 1.0;
  MonitorFeed feed(setup);
  for (int k = 0; k < 12000; ++k) feed.add(row_at(k * 0.004, k));
  feed.set_state("recorded");
  EXPECT_EQ(feed.rows_added(), 12000u);
  EXPECT_EQ(nlohmann::json::parse(feed.json(0, 100000))["rows"]["t"].size(), 12000u);
  // A reader asking again from `next` while `more` gets every row once, in order.
  std::uint64_t since = 0;
  int parts = 0;
  double expected_fz = 0.0;
  for (bool more = true; more; ++parts) {
    const auto doc = nlohmann::json::parse(feed.json(since));
    for (const auto& fz : doc["rows"]["fz"]) EXPECT_EQ(fz.get<double>(), expected_fz++);
    EXPECT_LE(doc["rows"]["t"].size(), MonitorFeed::kMaxRowsPerAnswer);
    since = doc["next"].get<std::uint64_t>();
    more = doc["more"].get<bool>();
  }
  EXPECT_EQ(expected_fz, 12000.0);
  EXPECT_EQ(parts, 3);  // 5000 + 5000 + 2000
}

TEST(MonitorFeed, LateAnswersAreAnswersLaterThanTheCycle) {
  MonitorSetup setup;
  setup.period_s = 0.004;
  MonitorFeed feed(setup);
  // Answer times (ms) and whether the cycle was answered; late: answered and above 4 ms.
  const double answer_ms[] = {0.1, 4.5, 3.99, 4.0, 12.0, 5.0, 0.2};
  const bool replied[] = {true, true, true, true, false, true, true};
  const std::uint64_t late_after[] = {0, 1, 1, 1, 1, 2, 2};  // 4.0 is not later than 4 ms
  const std::uint64_t answers_after[] = {1, 2, 3, 4, 4, 5, 6};
  for (int k = 0; k < 7; ++k) {
    MonitorRow r = row_at(k * 0.004, 0.0);
    r.answer_ms = answer_ms[k];
    r.replied = replied[k];
    feed.add(r);
  }
  feed.flush();
  const auto doc = nlohmann::json::parse(feed.json(0));
  EXPECT_EQ(doc["period_ms"], 4.0);
  for (int k = 0; k < 7; ++k) {
    EXPECT_EQ(doc["rows"]["late_answers"][k], late_after[k]) << k;
    EXPECT_EQ(doc["rows"]["answers"][k], answers_after[k]) << k;
  }
  EXPECT_TRUE(doc["rows"]["answer"][4].is_null());  // no answer, no answer time
}

TEST(MonitorFeed, TheTimelineMarksFaultsTripsRestartsAndTheStop) {
  MonitorSetup setup;
  MonitorFeed feed(setup);
  // 10 s at 4 ms: ok; a force fault 2.0..2.4 s flickering (ok for one cycle at 2.2 s); a guard trip at
  // 3 s; a restart at 5 s; a stale force from 7 s; three guard trips 8.0, 8.1, 8.2 s; the stop.
  std::uint64_t trips = 0, restarts = 0;
  for (int k = 0; k < 2500; ++k) {
    const double t = k * 0.004;
    MonitorRow r = row_at(t, 0.0);
    r.status = (t >= 2.0 && t < 2.4 && k != 550) ? 3 : t >= 7.0 ? 2 : 0;
    if (k == 750 || k == 2000 || k == 2025 || k == 2050) ++trips;
    if (k == 1250) ++restarts;
    r.guard_trips = trips;
    r.restarts = restarts;
    feed.add(r);
  }
  feed.set_state("ended", "the operator stopped it (SIGINT)");
  const auto doc = nlohmann::json::parse(feed.json(0));
  const auto& events = doc["events"];
  std::vector<std::tuple<std::string, double, std::uint64_t>> seen;
  for (const auto& e : events) seen.emplace_back(e["kind"], e["t"], e["count"]);
  const std::vector<std::tuple<std::string, double, std::uint64_t>> expected{
      {"force fault", 2.0, 2},  // the flicker merged into the first mark
      {"guard trip", 3.0, 1},  {"restart", 5.0, 1},      {"stale force", 7.0, 1},
      {"guard trip", 8.0, 3},  {"stop", 2499 * 0.004, 1}};
  ASSERT_EQ(seen.size(), expected.size()) << events.dump();
  for (std::size_t i = 0; i < seen.size(); ++i) {
    EXPECT_EQ(std::get<0>(seen[i]), std::get<0>(expected[i])) << i;
    EXPECT_NEAR(std::get<1>(seen[i]), std::get<1>(expected[i]), 1e-9) << i;
    EXPECT_EQ(std::get<2>(seen[i]), std::get<2>(expected[i])) << i;
  }
  EXPECT_EQ(events.back()["text"], "the operator stopped it (SIGINT)");
  EXPECT_NEAR(events[4]["last_t"].get<double>(), 8.2, 1e-9);
}

TEST(MonitorFeed, AReaderOnAnotherThreadSeesEveryRowOnceInOrder) {
  MonitorSetup setup;
  setup.window_s = 3600.0;
  MonitorFeed feed(setup);
  constexpr int kRows = 40000;
  std::atomic<bool> done{false};
  std::uint64_t since = 0, expected = 0, polls = 0;
  bool in_order = true;
  std::thread reader([&] {
    for (bool last = false, more = true; !last || more;) {
      last = done.load();
      const auto doc = nlohmann::json::parse(feed.json(since));
      for (const auto& seq : doc["rows"]["seq"]) in_order = in_order && seq.get<std::uint64_t>() == expected++;
      since = doc["next"].get<std::uint64_t>();
      more = doc["more"].get<bool>();
      ++polls;
    }
  });
  for (int k = 0; k < kRows; ++k) {
    MonitorRow r;
    r.t_s = k * 0.004;
    r.sequence = static_cast<std::uint64_t>(k);
    feed.add(r);
  }
  feed.flush();
  done = true;
  reader.join();
  EXPECT_TRUE(in_order);
  EXPECT_EQ(expected, static_cast<std::uint64_t>(kRows));
  EXPECT_GT(polls, 1u);
}

}  // namespace
}  // namespace deflex::runtime
