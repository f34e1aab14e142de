// The live monitor's feed: what a browser polling /data?since=N gets (every row once, in order, the
// window kept, NaN as null, text escaped), parsed with nlohmann-json as the page's JSON.parse would.
#include "deflex/runtime/monitor_feed.hpp"

#include <cmath>

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
  auto doc = nlohmann::json::parse(feed.json(0));
  EXPECT_EQ(doc["link"], "egm-\"joint\"");
  EXPECT_EQ(doc["next"], 250);
  ASSERT_EQ(doc["rows"]["t"].size(), 250u);
  EXPECT_DOUBLE_EQ(doc["rows"]["fz"][10].get<double>(), -390.0);
  EXPECT_NEAR(doc["rows"]["d2"][100].get<double>(), 0.01 * 0.4, 1e-9);
  // A poll from row 250 gets only what came since.
  for (int k = 250; k < 260; ++k) feed.add(row_at(k * 0.004, 0.0));
  doc = nlohmann::json::parse(feed.json(250));
  ASSERT_EQ(doc["rows"]["t"].size(), 10u);
  EXPECT_NEAR(doc["rows"]["t"][0].get<double>(), 1.0, 1e-12);
  // Rows older than the window are gone; a late browser gets the window.
  for (int k = 260; k < 1000; ++k) feed.add(row_at(k * 0.004, 0.0));
  doc = nlohmann::json::parse(feed.json(0));
  EXPECT_EQ(doc["next"], 1000);
  EXPECT_GE(doc["rows"]["t"][0].get<double>(), 3.996 - 2.0 - 1e-9);
  EXPECT_LE(doc["rows"]["t"].size(), 502u);
  // NaN (a value the cycle did not have) is null, and the state's text is escaped.
  feed.add(row_at(4.0, std::nan("")));
  feed.set_state("ended", "controller-silent: no \"usable\" message\n");
  doc = nlohmann::json::parse(feed.json(1000));
  EXPECT_TRUE(doc["rows"]["fz"][0].is_null());
  EXPECT_EQ(doc["state"], "ended");
  EXPECT_EQ(doc["stop_reason"], "controller-silent: no \"usable\" message");
}

TEST(MonitorFeed, ARecordedLogKeepsEverything) {
  MonitorSetup setup;
  setup.recorded = true;
  setup.window_s = 1.0;
  MonitorFeed feed(setup);
  for (int k = 0; k < 2000; ++k) feed.add(row_at(k * 0.004, 1.0));
  EXPECT_EQ(nlohmann::json::parse(feed.json(0))["rows"]["t"].size(), 2000u);
}

}  // namespace
}  // namespace deflex::runtime
