// SPDX-License-Identifier: Apache-2.0
// tools/urtwin.cpp — the emulator: loads a robot parameter file, starts the hard real-time loop
// (core/loop.c) and the UR network interfaces (net/), and runs until SIGINT/SIGTERM.
//
//   urtwin [--config FILE] [--overlay FILE]... [--set KEY=VALUE]... [--bind ADDR] [--port-offset N]
//          [--controller-version 5.19|3.15|…] [--rate 20000|10000] [--pacing tick|step|free|lockstep]
//          [--seed N] [--q0 q1,…,q6] [--faults FILE] [--boot ready|power-off] [--lcm] [--lcm-url URL] …
//          [--dds] [--dds-domain N] [--dds-config FILE] [--dds-prefix NS] …
//
// Exit status: 0 after a clean stop, 1 run-time failure (a port cannot be bound, …),
// 2 usage or configuration error.

#include <signal.h>
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "io_script.h"
#include "urt/core.h"
#include "urt/loop.h"
#include "urt/net/emulator.h"
#include "urt/net/dds_bridge.h"
#include "urt/net/lcm_bridge.h"
#include "urt/net/urp.h"
#include "urt/net/version.h"

namespace {

volatile sig_atomic_t g_stop = 0;
void on_signal(int) { g_stop = 1; }

struct Options {
  std::string config = "config/ur5.yaml";
  std::vector<std::string> sets;
  std::vector<std::string> overlays;  // --overlay FILE, applied in order before --set
  std::string faults;                 // --faults FILE: a fault scenario (urt/faults.h)
  std::string bind = "127.0.0.1";
  int port_offset = 0;
  std::string version = "5.19";
  double rate = 20000.0;
  std::string pacing = "tick";
  long long seed = -1;          // < 0: the config's
  std::string q0;
  std::string boot = "ready";
  bool lcm = false;
  std::string lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  std::string lcm_prefix = "URTWIN";
  double drive_rate = 1000.0;
  bool dds = false;
  int dds_domain = 0;
  std::string dds_config = "config/cyclonedds-lo.xml";
  std::string dds_prefix;
  double dds_timeout = 0.1;
  bool dds_node_info = false;
  int rt_priority = 0;
  bool lock_memory = false;
  bool local_control = false;
  bool no_remote_control = false;
  std::string programs_dir = "programs";
  std::string programs_alias = "/programs";  // the programs folder's name as clients see it
  std::string serial_number = "20235501783";
  std::string external_control_host = "127.0.0.1:50002";  // the URCap's host IP and port
  double stats_every = 10.0;    // seconds between loop statistics lines (0: never)
  std::string io_file;          // --io: a timed script of input levels (tools/io_script.h)
  std::string log_dir;          // --log-dir: where saveLog & co. write the controller's log
  std::vector<std::string> script_allow_hosts;
  int max_clients = URT_EMULATOR_MAX_CLIENTS;
  double out_budget_mib = URT_EMULATOR_OUT_BUDGET / 1048576.0;
};

// One line: the commands each ring could not take, by producer ("rtde 12, dashboard 0, …").
void print_ring_drops(const urt_loop_t* loop) {
  std::string line;
  for (int i = 0; i < urt_loop_producer_count(loop); i++) {
    line += (i ? ", " : "") + std::string(urt_loop_producer_name(loop, i)) + " " +
            std::to_string(urt_loop_producer_dropped(loop, i));
  }
  std::fprintf(stderr, "urtwin: commands dropped per ring: %s\n", line.c_str());
}

// One line: the physics thread's time per controller period so far, wall clock (counts time
// it was preempted) and its own CPU time, as quantiles and maximum, also as shares of the period.
void print_exec_stats(const urt_loop_stats_t& s, double period) {
  std::fprintf(stderr,
               "urtwin: physics per period: wall p50 %.0f us p99 %.0f us p99.9 %.0f us max %.0f us "
               "(max %.1f %% of %.0f us); cpu p50 %.0f us p99 %.0f us p99.9 %.0f us max %.0f us "
               "(max %.1f %%); refined steps %llu; periods at half the period or more: wall "
               "%llu cpu %llu of %llu\n",
               s.exec_p50 * 1e6, s.exec_p99 * 1e6, s.exec_p999 * 1e6, s.exec_max * 1e6,
               100.0 * s.exec_max / period, period * 1e6, s.cpu_p50 * 1e6, s.cpu_p99 * 1e6,
               s.cpu_p999 * 1e6, s.cpu_max * 1e6, 100.0 * s.cpu_max / period,
               (unsigned long long)s.refined_steps, (unsigned long long)s.exec_over_half,
               (unsigned long long)s.cpu_over_half, (unsigned long long)s.exec_periods);
}

// Raise the soft descriptor limit to the hard one: the caps, not a distribution's default of
// 1024, should be what refuses clients (8 ports at the cap hold 256). Best effort.
void raise_nofile_limit() {
  struct rlimit rl;
  if (getrlimit(RLIMIT_NOFILE, &rl) == 0 && rl.rlim_cur < rl.rlim_max) {
    rl.rlim_cur = rl.rlim_max;
    setrlimit(RLIMIT_NOFILE, &rl);
  }
}

// "127.0.0.1:50002" → host, port (1…65535).
int parse_host_port(const std::string& text, std::string* host, int* port) {
  size_t colon = text.rfind(':');
  if (colon == std::string::npos || colon == 0) {
    return -1;
  }
  char* end = nullptr;
  long p = std::strtol(text.c_str() + colon + 1, &end, 10);
  if (end == text.c_str() + colon + 1 || *end != '\0' || p < 1 || p > 65535) {
    return -1;
  }
  *host = text.substr(0, colon);
  *port = static_cast<int>(p);
  return 0;
}

int parse_q0(const std::string& text, double q[URT_NJ]) {
  std::vector<double> v;
  size_t pos = 0;
  while (pos <= text.size()) {
    size_t comma = text.find(',', pos);
    std::string item = text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    char* end = nullptr;
    double x = std::strtod(item.c_str(), &end);
    if (item.empty() || *end != '\0' || !std::isfinite(x)) {
      return -1;
    }
    v.push_back(x);
    if (comma == std::string::npos) {
      break;
    }
    pos = comma + 1;
  }
  if (v.size() != URT_NJ) {
    return -1;
  }
  for (int j = 0; j < URT_NJ; j++) {
    q[j] = v[j];
  }
  return 0;
}

long resident_kib() {
  FILE* f = std::fopen("/proc/self/statm", "r");
  long pages = 0, rss = 0;
  if (f) {
    if (std::fscanf(f, "%ld %ld", &pages, &rss) != 2) {
      rss = 0;
    }
    std::fclose(f);
  }
  return rss * (sysconf(_SC_PAGESIZE) / 1024);
}

// one line the tests parse (test_lcm.py: the inputs' counts)
void print_lcm_stats(const urt_lcm_bridge_t* b) {
  urt_lcm_stats_t n;
  urt_lcm_bridge_get_stats(b, &n);
  std::fprintf(stderr,
               "urtwin: lcm: status %llu (lost ticks %llu), drive %llu, publish errors %llu, "
               "commands received %llu accepted %llu rejected %llu dropped %llu, inputs "
               "received %llu accepted %llu rejected %llu dropped %llu, faults received %llu "
               "accepted %llu rejected %llu dropped %llu, fault truth %llu\n",
               (unsigned long long)n.status_sent, (unsigned long long)n.ticks_lost,
               (unsigned long long)n.drive_sent, (unsigned long long)n.publish_errors,
               (unsigned long long)n.cmd_received, (unsigned long long)n.cmd_accepted,
               (unsigned long long)n.cmd_rejected, (unsigned long long)n.cmd_dropped,
               (unsigned long long)n.io_received, (unsigned long long)n.io_accepted,
               (unsigned long long)n.io_rejected, (unsigned long long)n.io_dropped,
               (unsigned long long)n.fault_received, (unsigned long long)n.fault_accepted,
               (unsigned long long)n.fault_rejected, (unsigned long long)n.fault_dropped,
               (unsigned long long)n.truth_sent);
}

// one line the tests parse: "urtwin: dds: ticks N lost N drive N/N lost N, write errors N,
// commands received N accepted N invalid N refused N dropped N, trajectory ticks late N"
void print_dds_stats(const urt_dds_bridge_t* b) {
  urt_dds_stats_t d;
  urt_dds_bridge_get_stats(b, &d);
  std::fprintf(stderr,
               "urtwin: dds: ticks %llu lost %llu, drive messages %llu samples %llu lost %llu, "
               "write errors %llu, commands received %llu accepted %llu invalid %llu refused %llu "
               "dropped %llu, trajectory ticks late %llu\n",
               (unsigned long long)d.ticks_published, (unsigned long long)d.ticks_lost,
               (unsigned long long)d.drive_messages, (unsigned long long)d.drive_samples,
               (unsigned long long)d.drive_lost, (unsigned long long)d.write_errors,
               (unsigned long long)d.cmd_received, (unsigned long long)d.cmd_accepted,
               (unsigned long long)d.cmd_invalid, (unsigned long long)d.cmd_refused,
               (unsigned long long)d.cmd_dropped, (unsigned long long)d.traj_ticks_late);
}

}  // namespace

int main(int argc, char** argv) {
  // before any port opens: a client may connect and a supervisor may stop us at once
  struct sigaction sa {};
  sa.sa_handler = on_signal;
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);

  Options o;
  CLI::App app{"urtwin: a real-time emulator of a Universal Robots UR5 (physics + UR network ports)"};
  app.add_option("-c,--config", o.config, "robot parameter file")->capture_default_str();
  app.add_option("--overlay", o.overlays,
                 "apply an overlay file after the config, before --set (repeatable, in order)");
  app.add_option("-s,--set", o.sets, "override a config value, KEY=VALUE (repeatable)");
  app.add_option("--faults", o.faults,
                 "inject the fault scenario FILE (YAML, core/include/urt/faults.h) from start");
  app.add_option("--bind", o.bind, "IPv4 address every server binds")->capture_default_str();
  app.add_option("--port-offset", o.port_offset, "added to every port (several emulators per host)")
      ->check(CLI::Range(0, 30000))->capture_default_str();
  app.add_option("--controller-version", o.version,
                 "emulated controller: 5.x = e-Series at 500 Hz, 3.x = CB3 at 125 Hz")
      ->capture_default_str();
  app.add_option("--rate", o.rate, "physics rate [Hz]")->check(CLI::IsMember({10000.0, 20000.0}))
      ->capture_default_str();
  app.add_option("--pacing", o.pacing, "tick | step | free | lockstep")
      ->check(CLI::IsMember({"tick", "step", "free", "lockstep"}))->capture_default_str();
  app.add_option("--seed", o.seed, "sensor-noise RNG seed (default: the config's)");
  app.add_option("--q0", o.q0, "initial joint positions [rad], six comma-separated values");
  app.add_option("--boot", o.boot, "ready (RUNNING) or power-off")
      ->check(CLI::IsMember({"ready", "power-off"}))->capture_default_str();
  app.add_flag("--lcm", o.lcm, "publish status and drive messages on LCM, take commands");
  app.add_option("--lcm-url", o.lcm_url, "LCM provider URL (ttl=0 keeps traffic on this host)")
      ->capture_default_str();
  app.add_option("--lcm-prefix", o.lcm_prefix, "channel prefix: PREFIX_STATUS, _DRIVE, _COMMAND, _IO, _FAULT, _FAULT_TRUTH")
      ->capture_default_str();
  app.add_flag("--dds", o.dds, "publish the UR ROS 2 driver's topics on Cyclone DDS, take "
               "forward and trajectory commands");
  app.add_option("--dds-domain", o.dds_domain, "DDS domain (ROS_DOMAIN_ID)")
      ->check(CLI::Range(0, URT_DDS_MAX_DOMAIN))->capture_default_str();
  app.add_option("--dds-config", o.dds_config, "Cyclone DDS XML configuration (default: loopback only)")
      ->capture_default_str();
  app.add_option("--dds-prefix", o.dds_prefix, "namespace of every DDS topic (several emulators per domain)");
  app.add_flag("--dds-node-info", o.dds_node_info,
               "announce the ROS node \"urtwin\" on ros_discovery_info (ros2 node list; Iron and "
               "later, not Humble)");
  app.add_option("--dds-command-timeout", o.dds_timeout,
                 "forward position/velocity commands: stop the arm this long after the last [s]")
      ->check(CLI::Range(0.004, 10.0))->capture_default_str();
  app.add_option("--drive-rate", o.drive_rate, "drive sample rate of LCM and of DDS /urtwin/drive [Hz]")
      ->check(CLI::Range(0.0, 20000.0))->capture_default_str();
  app.add_option("--rt-priority", o.rt_priority, "SCHED_FIFO priority of the physics thread; the I/O and script threads get one less (0: none)")
      ->check(CLI::Range(0, 99))->capture_default_str();
  app.add_flag("--lock-memory", o.lock_memory, "mlockall and prefault the physics thread's stack");
  app.add_option("--programs-dir", o.programs_dir,
                 "where dashboard `load` finds programs (URScript text, .urp or .script)")
      ->capture_default_str();
  app.add_option("--programs-alias", o.programs_alias,
                 "the programs folder's absolute name as clients see it: a controller's "
                 "/programs, URSim's /ursim/programs (dashboard `load /ursim/programs/x.urp`)")
      ->check([](const std::string& s) {
        return !s.empty() && s[0] == '/' && s.size() < 200 ? std::string()
                                                           : std::string("an absolute path (starting with /) under 200 characters");
      })
      ->capture_default_str();
  app.add_flag("--local-control", o.local_control,
               "e-Series: the teach pendant has control (dashboard refuses state changes)");
  app.add_flag("--no-remote-control", o.no_remote_control,
               "e-Series: remote control disabled in Settings, URSim's default (`is in remote "
               "control` answers false, the dashboard refuses nothing)")
      ->excludes("--local-control");
  app.add_option("--serial-number", o.serial_number, "digits reported by `get serial number`")
      ->check([](const std::string& s) {
        return !s.empty() && s.find_first_not_of("0123456789") == std::string::npos
                   ? std::string()
                   : std::string("must be digits");
      })
      ->capture_default_str();
  app.add_option("--script-allow-host", o.script_allow_hosts,
                 "a host besides loopback that URScript's socket_open may dial, as the script "
                 "writes it (repeatable, at most 16)");
  app.add_option("--external-control-host", o.external_control_host,
                 "HOST:PORT an External Control node fetches its program from (request_program, "
                 "as the URCap does); loopback addresses only")
      ->check([](const std::string& s) {
        std::string host;
        int port = 0;
        return parse_host_port(s, &host, &port) == 0 ? std::string()
                                                     : std::string("expected IPv4:PORT");
      })
      ->capture_default_str();
  app.add_option("--log-dir", o.log_dir,
                 "an existing folder where the dashboard's saveLog, generate flight report and "
                 "generate support file write the controller's log (without it they are refused)")
      ->check(CLI::ExistingDirectory);
  app.add_option("--io", o.io_file,
                 "a YAML script of timed input levels (digital and analog inputs) played in "
                 "controller time: tools/io_script.h");
  app.add_option("--stats-every", o.stats_every, "seconds between loop statistics lines (0: never)")
      ->capture_default_str();
  app.add_option("--max-clients", o.max_clients,
                 "clients at once on each port; one more is accepted and closed at once")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app.add_option("--out-budget-mib", o.out_budget_mib,
                 "output buffers all clients together may hold [MiB]; beyond it messages are "
                 "dropped for the clients that do not read")
      ->check(CLI::Range(1.0, 4096.0))
      ->capture_default_str();
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int rc = app.exit(e);
    return rc == 0 ? 0 : 2;
  }

  if (o.script_allow_hosts.size() > 16) {
    std::fprintf(stderr, "urtwin: --script-allow-host: at most 16 hosts\n");
    return 2;
  }
  for (const auto& h : o.script_allow_hosts) {
    if (h.empty() || h.size() > 255) {
      std::fprintf(stderr, "urtwin: --script-allow-host '%s': expected a host of 1..255 bytes\n", h.c_str());
      return 2;
    }
  }

  urt_version_t version;
  if (urt_version_parse(o.version.c_str(), &version) != 0) {
    std::fprintf(stderr, "urtwin: --controller-version %s: expected 3.x or 5.x\n", o.version.c_str());
    return 2;
  }
  double q0[URT_NJ];
  if (!o.q0.empty() && parse_q0(o.q0, q0) != 0) {
    std::fprintf(stderr, "urtwin: --q0 %s: expected six finite comma-separated numbers\n", o.q0.c_str());
    return 2;
  }

  // the rate and seed are config values: pass them as overrides so the loader validates them
  std::vector<std::string> sets = o.sets;
  char buf[64];
  std::snprintf(buf, sizeof buf, "simulation.dt=%.17g", 1.0 / o.rate);
  sets.insert(sets.begin(), buf);
  if (o.seed >= 0) {
    std::snprintf(buf, sizeof buf, "simulation.seed=%lld", o.seed);
    sets.insert(sets.begin(), buf);
  }
  std::vector<const char*> overrides;
  for (const auto& s : sets) {
    overrides.push_back(s.c_str());
  }
  overrides.push_back(nullptr);

  // an emulator dials loopback only (an External Control node's fetch included)
  std::string ec_host;
  int ec_port = 0;
  parse_host_port(o.external_control_host, &ec_host, &ec_port);
  if (!urt_urcap_host_is_loopback(ec_host.c_str())) {
    std::fprintf(stderr,
                 "urtwin: --external-control-host %s: not a loopback address; urtwin only "
                 "connects to 127.0.0.0/8\n",
                 o.external_control_host.c_str());
    return 2;
  }

  std::vector<IoEvent> io_events;
  if (!o.io_file.empty()) {
    std::string ierr;
    if (!io_script_load(o.io_file, &io_events, &ierr)) {
      std::fprintf(stderr, "urtwin: --io: %s\n", ierr.c_str());
      return 2;
    }
  }

  urt_model_t* m = nullptr;
  char err[512];
  std::vector<const char*> overlays;
  for (const std::string& s : o.overlays) {
    overlays.push_back(s.c_str());
  }
  overlays.push_back(nullptr);
  if (urt_model_load_overlays(o.config.c_str(), overlays.data(), overrides.data(), &m, err,
                              sizeof err) != 0) {
    std::fprintf(stderr, "urtwin: %s\n", err);
    return 2;
  }

  urt_loop_config_t lc{};
  if (!o.faults.empty() &&
      urt_faults_load(m, o.faults.c_str(), &lc.faults, err, sizeof err) != 0) {
    std::fprintf(stderr, "urtwin: %s\n", err);
    urt_model_free(m);
    return 2;
  }
  lc.period = urt_version_period(&version);
  lc.pacing = o.pacing == "step"       ? URT_PACING_STEP
              : o.pacing == "free"     ? URT_PACING_FREE
              : o.pacing == "lockstep" ? URT_PACING_LOCKSTEP
                                       : URT_PACING_TICK;
  lc.powered = o.boot == "ready";
  lc.rt_priority = o.rt_priority;
  lc.lock_memory = o.lock_memory;
  lc.drive_rate = o.lcm || o.dds ? o.drive_rate : 0.0;
  urt_loop_t* loop = nullptr;
  int rc = urt_loop_create(m, &lc, o.q0.empty() ? nullptr : q0, &loop, err, sizeof err);
  if (rc != 0) {
    std::fprintf(stderr, "urtwin: %s\n", err);
    urt_model_free(m);
    return 2;
  }

  urt_emulator_config_t ec{};
  ec.bind = o.bind.c_str();
  ec.port_offset = o.port_offset;
  ec.version = version;
  ec.programs_dir = o.programs_dir.c_str();
  ec.programs_alias = o.programs_alias.c_str();
  ec.log_dir = o.log_dir.empty() ? nullptr : o.log_dir.c_str();
  ec.local_control = o.local_control;
  ec.remote_control_off = o.no_remote_control;
  ec.serial_number = o.serial_number.c_str();
  ec.external_control_host = ec_host.c_str();
  ec.external_control_port = ec_port;
  ec.rt_priority = o.rt_priority > 1 ? o.rt_priority - 1 : 0;  // just below the physics
  ec.max_clients = o.max_clients;
  ec.out_budget = static_cast<size_t>(o.out_budget_mib * 1048576.0);
  raise_nofile_limit();
  std::vector<const char*> allow_hosts;
  for (const auto& h : o.script_allow_hosts) {
    allow_hosts.push_back(h.c_str());
  }
  ec.script_allow_hosts = allow_hosts.data();
  ec.n_script_allow_hosts = static_cast<int>(allow_hosts.size());
  urt_emulator_t* emu = nullptr;
  if (urt_emulator_create(loop, &ec, &emu, err, sizeof err) != 0) {
    std::fprintf(stderr, "urtwin: %s\n", err);
    urt_loop_destroy(loop);
    urt_model_free(m);
    return 1;
  }

  urt_lcm_bridge_t* bridge = nullptr;
  if (o.lcm) {
    urt_lcm_config_t bc{};
    urt_lcm_config_default(&bc);
    bc.url = o.lcm_url.c_str();
    std::string st = o.lcm_prefix + "_STATUS", dr = o.lcm_prefix + "_DRIVE",
                cm = o.lcm_prefix + "_COMMAND", io = o.lcm_prefix + "_IO",
                fa = o.lcm_prefix + "_FAULT", ft = o.lcm_prefix + "_FAULT_TRUTH";
    bc.status_channel = st.c_str();
    bc.fault_channel = fa.c_str();
    bc.fault_truth_channel = ft.c_str();
    bc.drive_channel = dr.c_str();
    bc.command_channel = cm.c_str();
    bc.io_channel = io.c_str();
    bc.lockstep = lc.pacing == URT_PACING_LOCKSTEP;
    if (urt_lcm_bridge_create(loop, &bc, &bridge, err, sizeof err) != 0) {
      std::fprintf(stderr, "urtwin: lcm: %s\n", err);
      urt_emulator_destroy(emu);
      urt_loop_destroy(loop);
      urt_model_free(m);
      return 1;
    }
  }

  urt_dds_bridge_t* dds = nullptr;
  if (o.dds) {
    urt_dds_config_t dc;
    urt_dds_config_default(&dc);
    dc.domain = o.dds_domain;
    dc.config_file = o.dds_config.empty() ? nullptr : o.dds_config.c_str();
    dc.prefix = o.dds_prefix.c_str();
    dc.command_timeout = o.dds_timeout;
    dc.local_control = o.local_control;
    dc.node_info = o.dds_node_info;
    dc.rt_priority = ec.rt_priority;  // as the I/O threads
    int drc = urt_dds_bridge_create(loop, &dc, &dds, err, sizeof err);
    if (drc != 0) {
      std::fprintf(stderr, "urtwin: %s\n", err);
      urt_lcm_bridge_destroy(bridge);
      urt_emulator_destroy(emu);
      urt_loop_destroy(loop);
      urt_model_free(m);
      return drc == URT_EIO || drc == URT_ENOMEM ? 1 : 2;
    }
  }

  urt_loop_start(loop);
  std::unique_ptr<IoPlayer> io;
  if (!o.io_file.empty()) {
    io = std::make_unique<IoPlayer>(loop, io_events);
    std::string ierr;
    if (!io->start(&ierr)) {
      std::fprintf(stderr, "urtwin: %s\n", ierr.c_str());
      return 1;
    }
  }
  urt_emulator_start(emu);
  if (bridge) {
    urt_lcm_bridge_start(bridge);
  }
  if (dds) {
    urt_dds_bridge_start(dds);
  }
  std::fprintf(stderr,
               "urtwin: %s, controller %d.%d.%d (%s, %.0f Hz), physics %.0f Hz, pacing %s, on %s "
               "ports 29999, 30001-30004 (offset %d)%s\n",
               m->name, version.major, version.minor, version.bugfix,
               urt_version_is_eseries(&version) ? "e-Series" : "CB3", 1.0 / lc.period, 1.0 / m->dt,
               o.pacing.c_str(), o.bind.c_str(), o.port_offset,
               o.lcm && o.dds ? ", LCM on, DDS on" : o.lcm ? ", LCM on" : o.dds ? ", DDS on" : "");

  double since_stats = 0.0;
  while (!g_stop && !urt_emulator_shutdown_requested(emu)) {
    usleep(100000);
    since_stats += 0.1;
    if (o.stats_every > 0 && since_stats >= o.stats_every) {
      since_stats = 0.0;
      urt_loop_stats_t s;
      urt_loop_get_stats(loop, &s);
      std::fprintf(stderr,
                   "urtwin: ticks %llu, overruns %llu, missed periods %llu, commands dropped %llu, "
                   "physics per period last %.0f us max %.0f us, resident %ld KiB\n",
                   (unsigned long long)s.ticks, (unsigned long long)s.overruns,
                   (unsigned long long)s.missed_periods, (unsigned long long)s.cmd_dropped,
                   s.exec_last * 1e6, s.exec_max * 1e6, resident_kib());
      urt_emulator_stats_t es;
      urt_emulator_get_stats(emu, &es);
      std::fprintf(stderr,
                   "urtwin: clients %llu, refused at the cap %llu, refused for descriptors %llu, "
                   "output buffers %llu KiB (%llu growths refused)\n",
                   (unsigned long long)es.clients, (unsigned long long)es.refused_cap,
                   (unsigned long long)es.refused_fds, (unsigned long long)(es.out_bytes / 1024),
                   (unsigned long long)es.out_refused);
      print_exec_stats(s, urt_loop_period(loop));
      print_ring_drops(loop);
      if (dds) {
        print_dds_stats(dds);
      }
    }
  }

  if (dds) {
    urt_dds_bridge_stop(dds);
    print_dds_stats(dds);
  }
  if (bridge) {
    urt_lcm_bridge_stop(bridge);
    print_lcm_stats(bridge);
  }
  if (io) {
    io->stop();
    std::fprintf(stderr, "urtwin: --io: %zu of %zu input changes played, %zu dropped\n",
                 io->played(), io_events.size(), io->dropped());
  }
  urt_emulator_stop(emu);
  urt_loop_stop(loop);
  urt_emulator_stats_t es;
  urt_emulator_get_stats(emu, &es);
  std::fprintf(stderr,
               "urtwin: urscript per tick: cpu p50 %.1f us p99 %.1f us p99.9 %.1f us max %.1f us "
               "over %llu ticks\n",
               es.script_tick.p50 * 1e6, es.script_tick.p99 * 1e6, es.script_tick.p999 * 1e6,
               es.script_tick.max * 1e6, (unsigned long long)es.script_tick.ticks);
  std::fprintf(stderr, "urtwin: urscript slices taken late: %llu (at most %llu ticks behind)\n",
               (unsigned long long)es.script_tick.late_slices,
               (unsigned long long)es.script_tick.late_max);
  std::fprintf(stderr, "urtwin: urscript threads preempted for computing a whole slice: %llu\n",
               (unsigned long long)es.script_tick.preempted);
  std::fprintf(stderr,
               "urtwin: urscript program start: arrival to PROGRAM_XXX_STARTED p50 %.1f ms max "
               "%.1f ms over %llu programs (compile p50 %.1f ms max %.1f ms)\n",
               es.script_tick.start_p50 * 1e3, es.script_tick.start_max * 1e3,
               (unsigned long long)es.script_tick.starts, es.script_tick.compile_p50 * 1e3,
               es.script_tick.compile_max * 1e3);
  std::fprintf(stderr,
               "urtwin: urscript socket_open waited for a local server's accept: %llu times (at "
               "most %llu ticks)\n",
               (unsigned long long)es.script_tick.accept_waits,
               (unsigned long long)es.script_tick.accept_wait_max);
  urt_loop_stats_t s;
  urt_loop_get_stats(loop, &s);
  std::fprintf(stderr, "urtwin: stopped after %llu ticks, %llu overruns, %llu missed periods\n",
               (unsigned long long)s.ticks, (unsigned long long)s.overruns,
               (unsigned long long)s.missed_periods);
  print_exec_stats(s, urt_loop_period(loop));
  print_ring_drops(loop);
  urt_dds_bridge_destroy(dds);
  urt_lcm_bridge_destroy(bridge);
  urt_emulator_destroy(emu);
  urt_loop_destroy(loop);
  urt_model_free(m);
  return 0;
}
