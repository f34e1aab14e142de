// `deflex online`: deflex on a controller link (ABB EGM position guidance or path correction, KUKA RSI
// axis correction, ROS-Industrial simple message, FANUC Stream Motion). This file only turns options
// into a session: the options are the rows of the library's settings table (runtime/session_settings.hpp,
// which checks every value), the force source and its tare are the library's (session_force.hpp), the
// session runs the link (runtime/session.hpp); what is left here are the files the command reads, its
// outputs, the live page and the signals. The exit code is the session's stop reason's (docs/online.md,
// "Faults and exit codes").
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <deque>
#include <memory>
#include <thread>
#include <vector>

#include <fmt/format.h>

#include "cli_util.hpp"
#include "command.hpp"
#include "deflex/force/force_spec.hpp"
#include "deflex/monitor/cycle_log_reader.hpp"
#include "deflex/monitor/monitor_server.hpp"
#include "deflex/robotfile/robot_io.hpp"
#include "deflex/runtime/session.hpp"
#include "deflex/runtime/session_force.hpp"
#include "deflex/runtime/session_settings.hpp"
#include "deflex/text/errors.hpp"
#include "field_log.hpp"

namespace deflex::cli {
namespace {

// The session a stop signal goes to: request_stop() is an atomic counter, safe in a signal handler, so
// the loop sees the request at its next cycle (a planned stop ramps down first; a second signal ends
// the session at once).
std::atomic<runtime::Session*> g_session{nullptr};
extern "C" void on_stop_signal(int /*signal*/) {
  if (runtime::Session* s = g_session.load()) s->request_stop();
}

struct OnlineOpts {
  // The session's settings (runtime/session_settings.hpp): one text or flag a row of the table.
  std::vector<std::string> texts = std::vector<std::string>(runtime::session_settings().size());
  std::deque<bool> flags = std::deque<bool>(runtime::session_settings().size(), false);
  std::vector<CLI::Option*> options = std::vector<CLI::Option*>(runtime::session_settings().size(), nullptr);
  // What only the command line has: the files it reads, its outputs, the live page.
  std::string link, robot, sensor, program, strategy = "online", force_model;
  bool json = false;
  std::string monitor;
  bool monitor_remote = false, log_report = false;
  double monitor_linger_s = 0.0;
  LogOptions log_options;
};

// An option a row of the settings table: its help, unit, range, default and links from the table.
void add_setting_options(CLI::App& sub, OnlineOpts& o) {
  const auto settings = runtime::session_settings();
  for (std::size_t i = 0; i < settings.size(); ++i) {
    const runtime::SessionSetting& s = settings[i];
    const std::string name(s.option);
    if (s.type == runtime::SettingType::kFlag) {
      o.options[i] = sub.add_flag(name, o.flags[i], runtime::option_help(s));
      continue;
    }
    const std::string_view unit = s.option_unit.empty() ? s.unit : s.option_unit;
    std::string type = s.type == runtime::SettingType::kText      ? "TEXT"
                       : s.type == runtime::SettingType::kInteger ? "N"
                                                                  : std::string(unit.empty() ? "NUMBER" : unit);
    o.options[i] = sub.add_option(name, o.texts[i], runtime::option_help(s))
                       ->type_name(type)
                       ->default_str(runtime::option_default(s));
  }
  sub.get_option("--force-source")->required();
}

// The settings given on the command line, in the key's unit, for the library to check and apply.
std::vector<runtime::GivenSetting> given_settings(const OnlineOpts& o) {
  std::vector<runtime::GivenSetting> given;
  const auto settings = runtime::session_settings();
  for (std::size_t i = 0; i < settings.size(); ++i) {
    const runtime::SessionSetting& s = settings[i];
    if (o.options[i]->count() == 0) continue;
    if (s.type == runtime::SettingType::kFlag) {
      given.push_back({&s, !s.flag_inverted});
    } else {
      given.push_back({&s, runtime::option_value(s, o.texts[i])});
    }
  }
  return given;
}

// Where --log-report writes: beside the log, .html for its .csv.
std::string log_report_path(const std::string& log) {
  const std::string csv = ".csv";
  if (log.size() > csv.size() && log.compare(log.size() - csv.size(), csv.size(), csv) == 0) {
    return log.substr(0, log.size() - csv.size()) + ".html";
  }
  return log + ".html";
}

// The session's log lines go to the field log.
runtime::LogSink log_sink(const std::shared_ptr<spdlog::logger>& log) {
  return [log](runtime::LogLevel level, const std::string& text) {
    switch (level) {
      case runtime::LogLevel::kInfo:
        log->info("{}", text);
        break;
      case runtime::LogLevel::kWarn:
        log->warn("{}", text);
        break;
      case runtime::LogLevel::kError:
        log->error("{}", text);
        break;
    }
  };
}

runtime::SessionConfig online_session_config(const OnlineOpts& o) {
  runtime::SessionConfig config = runtime::make_session_config(o.link, o.strategy, given_settings(o));
  config.monitor = !o.monitor.empty();
  if (o.log_report && config.log_path.empty()) {
    throw InputError("option --log-report: needs --log (the report draws the log)");
  }
  if (!o.monitor.empty()) (void)monitor::parse_monitor_address(o.monitor, o.monitor_remote, "--monitor");
  if (o.monitor_remote && o.monitor.empty()) throw InputError("option --monitor-remote: only with --monitor");
  return config;
}

// The monitor binds before anything is answered: a port in use is an error now, not mid-session.
std::unique_ptr<monitor::MonitorServer> start_monitor(const OnlineOpts& o, const runtime::SessionConfig& config,
                                                      runtime::Session& session,
                                                      const std::shared_ptr<spdlog::logger>& log) {
  if (!config.monitor) return nullptr;
  auto server = std::make_unique<monitor::MonitorServer>(
      session.monitor_feed(), monitor::parse_monitor_address(o.monitor, o.monitor_remote, "--monitor"));
  log->info("monitor on {} (the last {:g} s of the session, 10 updates a second)", server->url(),
            config.monitor_window_s);
  return server;
}

void install_stop_handlers() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

// The summary's lines: info when the session ended as planned, errors when not.
void log_summary(const runtime::SessionSummary& summary, const std::shared_ptr<spdlog::logger>& log) {
  const bool planned = summary.exit_code == 0;
  for (std::string_view text = summary.text; !text.empty();) {
    const std::size_t eol = text.find('\n');
    const std::string_view line = text.substr(0, eol);
    if (planned) {
      log->info("{}", line);
    } else {
      log->error("{}", line);
    }
    text = eol == std::string_view::npos ? std::string_view() : text.substr(eol + 1);
  }
}

int online_exit_code(const runtime::SessionSummary& summary, const FieldLogHealth& log_health) {
  int exit_code = summary.exit_code;
  // A session that ended as planned but whose cycle log could not be written failed all the same.
  if (!summary.output_error.empty() && exit_code == 0) exit_code = 1;
  if (log_health.failed()) {
    // The summary's lines may not have reached the file: say so where they did arrive.
    std::fprintf(stderr, "deflex online: %s: the lines after it are on stderr only\n", log_health.error().c_str());
    if (exit_code == 0) exit_code = 1;
  }
  return exit_code;
}

void write_online_log_report(const runtime::SessionConfig& config, const runtime::SessionSummary& summary,
                             const std::shared_ptr<spdlog::logger>& log) {
  const std::string report = log_report_path(config.log_path);
  write_output_file(
      report,
      monitor::monitor_report(*monitor::read_cycle_log_feed(config.log_path),
                              fmt::format("deflex online: {} ({})", config.log_path, summary.reason_text)),
      "option --log-report");
  log->info("the session's charts: {}", report);
}

void run_online(const OnlineOpts& o, int& exit_code) {
  const runtime::SessionConfig config = online_session_config(o);
  const runtime::LinkKindInfo& info = runtime::link_kind(config.link);
  const RobotModel model = load_cli_robot("online", o.robot);
  SensorConfig sensor = load_sensor_config_or_defaults(o.sensor);
  std::unique_ptr<ForceModel> force_model;
  if (!o.force_model.empty()) force_model = parse_force_spec(o.force_model);
  std::shared_ptr<const JointTrajectory> program;
  if (!o.program.empty())
    program = std::make_shared<const JointTrajectory>(JointTrajectory::read_csv(o.program, model));
  const auto log_health = std::make_shared<FieldLogHealth>();
  const auto log = make_field_logger("online", o.log_options, log_health);
  const OpenedForceSource force = runtime::open_session_force(config, model, sensor, program.get(), log_sink(log));
  SteadyClock clock;
  runtime::Session session(config, model, sensor, program, force_model.get(), force.source.get(), clock, {},
                           log_sink(log));
  const std::unique_ptr<monitor::MonitorServer> monitor_server = start_monitor(o, config, session, log);
  if (info.streams_program && !model.has_max_speed()) {
    log->warn(
        "the robot file gives no joint speed limits, so the program's speeds were not checked (add max_speed "
        "to the robot file)");
  }
  log->info("deflex online: {}; robot {}; sensor {}; force from {}. Stop with Ctrl-C.", session.describe(),
            model.name(), sensor.source, force.description);

  g_session.store(&session);
  // A field log that cannot be written ends the session as the cycle log's failure does (exit 1).
  log_health->on_failure([](const std::string& text) {
    if (runtime::Session* s = g_session.load()) s->report_output_failure(text);
  });
  struct Unhook {  // the handlers never see a session that is gone, however this function is left
    ~Unhook() { g_session.store(nullptr); }
  } unhook;
  install_stop_handlers();
  (void)session.run(0.0);  // real time is asked for (and refused, exit 2) before anything is answered
  if (config.realtime.enabled) log->info("real time: {}", session.realtime_text());
  while (!session.ended()) (void)session.run(0.1);
  const runtime::SessionSummary& summary = session.finish();
  log_summary(summary, log);
  if (o.json) {
    nlohmann::json doc = nlohmann::json::parse(summary.json_text);
    print_json(doc);
  }
  exit_code = online_exit_code(summary, *log_health);
  if (o.log_report && summary.output_error.empty()) write_online_log_report(config, summary, log);
  if (monitor_server && o.monitor_linger_s > 0.0) {
    log->info("monitor: the page stays up {:g} s more (--monitor-linger-s)", o.monitor_linger_s);
    std::this_thread::sleep_for(std::chrono::duration<double>(o.monitor_linger_s));
  }
}

void setup_online(CLI::App& sub, int& exit_code) {
  auto o = std::make_shared<OnlineOpts>();
  std::string link_help = "Controller link:";
  for (const runtime::LinkKindInfo& k : runtime::link_kinds()) link_help += fmt::format(" {} ({});", k.name, k.help);
  sub.add_option("--link", o->link, link_help)->required();
  sub.add_option("--robot", o->robot, kRobotHelp);
  sub.add_option("--sensor-config", o->sensor,
                 "Force-sensor YAML (docs/online.md); default: identity crosstalk, no payload, no bias, at the flange");
  sub.add_option("--program", o->program,
                 "Streaming links: the nominal joint trajectory deflex streams, CSV t_s,q1_deg..qN_deg (deflex offline "
                 "--nominal-trajectory / --joint-trajectory write one)");
  sub.add_option("--strategy", o->strategy,
                 "online (the paper's), hybrid (--program is the offline-compensated one; corrects measured minus "
                 "--force), predictive (wrench predicted where the command is executed), none (stream only)")
      ->capture_default_str();
  sub.add_option("--force", o->force_model,
                 "Force model of the process, a pose model: ldbb:pivot_mm=X;Y;Z,force_N=F,mode=push|pull or "
                 "constant:fx_N=.. (hybrid: required; predictive: optional)");
  add_setting_options(sub, *o);
  sub.add_flag("--log-report", o->log_report,
               "At the end, write the monitor's charts of the whole --log beside it (LOG with .html for .csv): a "
               "static page for a commissioning report");
  sub.add_option("--monitor", o->monitor,
                 "Serve a live page of the session at [ADDR:]PORT (default address 127.0.0.1; port 0 = any free one): "
                 "forces, corrections against their bounds, link health, 10 updates a second");
  sub.add_flag("--monitor-remote", o->monitor_remote,
               "Allow --monitor on an address other hosts can reach (the page shows the cell's data)");
  sub.add_option("--monitor-linger-s", o->monitor_linger_s,
                 "Keep the live page up this long after the session ended, so its stop reason can be read, s");
  sub.add_flag("--json", o->json, "At the end, print one JSON document of the counters and timing on stdout");
  add_log_options(sub, o->log_options);
  sub.callback([o, &exit_code] { run_online(*o, exit_code); });
}

}  // namespace

DEFLEX_COMMAND(
    "online",
    "Online compensation on a controller link (--link egm-joint|egm-path|rsi|simple-message|fanuc-j519|"
    "motoros2-rt|ur-rtde): condition force samples and answer the controller, never beyond the bound of the nominal",
    setup_online, 40);

}  // namespace deflex::cli
