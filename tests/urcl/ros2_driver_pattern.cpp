// SPDX-License-Identifier: Apache-2.0
// tests/urcl/ros2_driver_pattern.cpp — the UR ROS 2 driver's use of URCL, as a test against urtwin
// (issue 9, acceptance "the ROS 2 driver's pattern"). ROS 2 is not in Debian bookworm, so the
// driver cannot run here; this program makes the calls its hardware interface makes
// (../shared/docs/external_control.md §5.1), on URCL's public API only:
//
//   1. the full driver, headless, with the driver's RTDE recipes; read() blocks on the next
//      RTDE package (500 Hz on e-Series), write() sends a servoj target with a 10 ms receive
//      timeout, for 30 s of a slow sine on the wrist; the tracking is checked (lag = lookahead
//      time within 4 ms, residual after the lag ≤ 1e-3 rad);
//   2. a 3-point cubic spline forwarded on the trajectory socket (50003), kept alive by FORWARD
//      NOOPs with the passthrough controller's 10 ms timeout (5000 / update rate), until URCL's
//      trajectory-done callback reports TRAJECTORY_RESULT_SUCCESS;
//   3. then no more writes: the external-control program must end by its own receive timeout,
//      and the reverse socket (50001) close.
//
// Usage: ros2_driver_pattern ROBOT_IP SCRIPT_FILE [SERVO_SECONDS]   (run from URCL's source copy)
// Exit 0 when every check holds; 1 with the failed check on stderr. Prints the figures.
#include <ur_client_library/rtde/data_package.h>
#include <ur_client_library/ur/dashboard_client.h>
#include <ur_client_library/ur/ur_driver.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>
#include <vector>

using namespace urcl;
using Clock = std::chrono::steady_clock;

namespace {

// The driver's recipes (ur_robot_driver 7.0.0 resources/rtde_{output,input}_recipe.txt, as
// external_control.md §5.1 lists them): every field is read each cycle, a missing one throws.
const std::vector<std::string> kOutputs = {
    "timestamp", "actual_q", "actual_qd", "speed_scaling", "target_speed_fraction",
    "runtime_state", "actual_TCP_force", "actual_TCP_pose", "target_TCP_pose",
    "actual_digital_input_bits", "actual_digital_output_bits", "standard_analog_input0",
    "standard_analog_input1", "standard_analog_output0", "standard_analog_output1",
    "analog_io_types", "tool_mode", "tool_analog_input_types", "tool_analog_input0",
    "tool_analog_input1", "tool_output_voltage", "tool_output_current", "tool_temperature",
    "robot_mode", "safety_mode", "robot_status_bits", "safety_status_bits", "actual_current",
    "tcp_offset", "payload", "payload_cog", "payload_inertia"};
const std::vector<std::string> kInputs = {
    "speed_slider_mask", "speed_slider_fraction", "standard_digital_output_mask",
    "standard_digital_output", "configurable_digital_output_mask", "configurable_digital_output",
    "tool_digital_output_mask", "tool_digital_output", "standard_analog_output_mask",
    "standard_analog_output_type", "standard_analog_output_0", "standard_analog_output_1"};

constexpr uint32_t kPlaying = 2;  // RTDE runtime_state PLAYING
// Servo phases started at most: on this shared 2-vCPU VM a client at SCHED_FIFO still goes
// 12–16 ms without a package now and then under load (the host preempts the vCPU)
constexpr int kAttempts = 4;

std::atomic<bool> g_program_running{false};
std::atomic<int> g_program_drops{0};
std::atomic<int> g_trajectory_result{-2};  // -2: no callback yet

[[noreturn]] void fail(const std::string &what) {
  std::fprintf(stderr, "ros2_driver_pattern: FAILED: %s\n", what.c_str());
  std::exit(1);
}

// the servo phase's command for wrist 3: a slow sine about where it started
double sine(double centre, double t) { return centre + 0.2 * std::sin(2.0 * M_PI * 0.2 * t); }

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct Reader {
  UrDriver &driver;
  rtde_interface::DataPackage pkg;
  vector6d_t q{};
  uint32_t runtime_state = 0;
  double timestamp = 0.0;
  long missed = 0;

  explicit Reader(UrDriver &d) : driver(d), pkg(d.getRTDEOutputRecipe()) {}

  // read(): the driver blocks on the next package; a miss is counted, as the driver logs it
  bool read() {
    if (!driver.getDataPackage(pkg)) {
      missed++;
      return false;
    }
    if (!pkg.getData("actual_q", q) || !pkg.getData("runtime_state", runtime_state) ||
        !pkg.getData("timestamp", timestamp)) {
      fail("the RTDE package lacks actual_q, runtime_state or timestamp");
    }
    return true;
  }
};

// the gap this client saw is a lower bound of the gap between its writes' arrivals, which also
// wait for its processing and the socket (a tick or two): within 2 ticks of the timeout the
// controller's timeout is the client's doing
bool held_back(double max_gap, unsigned timeout_ms, double rate) {
  return max_gap >= 1e-3 * timeout_ms - 2.0 / rate - 1e-9;
}

// after a program ended by its receive timeout: send it again and wait until it plays and the
// reverse socket is back, as the driver's resend_robot_program service does
void resend_program(UrDriver &driver, Reader &rd, const char *phase) {
  if (!driver.sendRobotProgram()) {
    fail(std::string(phase) + ": the program could not be resent");
  }
  const auto t_resend = Clock::now();
  while (!(rd.read() && rd.runtime_state == kPlaying && g_program_running.load() &&
           driver.isReverseInterfaceConnected())) {
    if (seconds_since(t_resend) > 15.0) {
      fail(std::string(phase) + ": the resent program did not connect within 15 s");
    }
  }
}

struct Phase {
  bool dropped = false;   // the program left PLAYING, or a write failed
  double max_gap = 0.0;   // the largest gap between two packages this client read [s]
  int result = -2;        // URCL's trajectory result (-2: none)
  double took = 0.0;      // controller time from the points' sending to the result [s]
  double end_err = 0.0;   // max |q - last point| after 0.5 s of settling [rad]
};

// One attempt of the spline phase: 3 points from where the arm is, forwarded on 50003, then
// FORWARD NOOPs with the passthrough controller's timeout until the result and 0.5 s after it
// (the arm settling on the last point).
Phase spline_phase(UrDriver &driver, Reader &rd, unsigned timeout_ms) {
  Phase ph;
  while (!rd.read()) {
  }
  const vector6d_t start = rd.q;
  std::vector<vector6d_t> pts(3, start), vel(3, vector6d_t{0, 0, 0, 0, 0, 0});
  pts[0][5] = start[5] + 0.10;
  vel[0][5] = 0.10;
  pts[1][5] = start[5] + 0.20;
  vel[1][5] = 0.05;
  pts[2][5] = start[5] + 0.25;  // ends at rest
  pts[2][0] = start[0] - 0.05;
  const double dt[3] = {1.0, 1.0, 1.0};
  g_trajectory_result = -2;
  const int drops_before = g_program_drops.load();
  if (!driver.writeTrajectoryControlMessage(control::TrajectoryControlMessage::TRAJECTORY_START, 3,
                                            RobotReceiveTimeout::millisec(timeout_ms))) {
    fail("trajectory: TRAJECTORY_START");
  }
  for (int k = 0; k < 3; k++) {
    if (!driver.writeTrajectorySplinePoint(pts[k], vel[k], static_cast<float>(dt[k]))) {
      fail("trajectory: a spline point could not be written on 50003");
    }
  }
  const double ts_traj = rd.timestamp;
  double last_ts = rd.timestamp, ts_done = -1.0;
  while (ts_done < 0.0 || rd.timestamp - ts_done < 0.5) {
    if (rd.read()) {
      ph.max_gap = std::max(ph.max_gap, rd.timestamp - last_ts);
      last_ts = rd.timestamp;
      if (rd.runtime_state != kPlaying || g_program_drops.load() != drops_before ||
          !driver.writeTrajectoryControlMessage(control::TrajectoryControlMessage::TRAJECTORY_NOOP,
                                                -1, RobotReceiveTimeout::millisec(timeout_ms))) {
        ph.dropped = true;
        return ph;
      }
    }
    if (ts_done < 0.0 && g_trajectory_result.load() != -2) {
      ts_done = rd.timestamp;
      ph.took = ts_done - ts_traj;
    }
    if (rd.timestamp - ts_traj > 15.0) {
      fail("trajectory: no result within 15 s of controller time");
    }
  }
  ph.result = g_trajectory_result.load();
  for (int j = 0; j < 6; j++) {
    ph.end_err = std::max(ph.end_err, std::fabs(rd.q[j] - pts[2][j]));
  }
  return ph;
}

}  // namespace

int main(int argc, char *argv[]) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: %s ROBOT_IP SCRIPT_FILE [SERVO_SECONDS]\n", argv[0]);
    return 2;
  }
  const std::string ip = argv[1];
  const double servo_seconds = argc > 3 ? std::atof(argv[3]) : 30.0;
  urcl::setLogLevel(urcl::LogLevel::WARN);

  // the robot_state_helper's part: power on and release the brakes over the dashboard
  DashboardClient dash(ip);
  if (!dash.connect(5) || !dash.commandPowerOn(std::chrono::seconds(30)) ||
      !dash.commandBrakeRelease()) {
    fail("dashboard: power on / brake release");
  }

  UrDriverConfiguration cfg;
  cfg.robot_ip = ip;
  cfg.script_file = argv[2];
  cfg.output_recipe = kOutputs;
  cfg.input_recipe = kInputs;
  cfg.headless_mode = true;
  cfg.servoj_gain = 2000;
  cfg.servoj_lookahead_time = 0.03;
  cfg.handle_program_state = [](bool running) {
    if (!running && g_program_running.load()) {
      g_program_drops++;
    }
    g_program_running = running;
  };
  UrDriver driver(cfg);
  driver.registerTrajectoryDoneCallback(
      [](control::TrajectoryResult r) { g_trajectory_result = static_cast<int>(r); });
  const double rate = driver.getControlFrequency();
  // the driver's timeouts at its update rate: passthrough NOOP 5000 / rate ms (10 ms at 500 Hz);
  // the servo pattern uses the same 10 ms
  const unsigned timeout_ms = static_cast<unsigned>(std::lround(5000.0 / rate));

  driver.startRTDECommunication();
  Reader rd(driver);
  const auto t_boot = Clock::now();
  while (!(g_program_running.load() && driver.isReverseInterfaceConnected())) {
    rd.read();
    if (seconds_since(t_boot) > 15.0) {
      fail("the external-control program did not connect within 15 s");
    }
  }

  // ---- 1. servoj passthrough at the RTDE cadence ---------------------------------------------
  // A program that ends because the client itself went quiet for about the receive timeout did what
  // a controller does; that is the machine holding this process (or the stream) back, not a
  // fault of the emulator's: such an attempt is reported and the phase starts again with the
  // program resent (at most kAttempts). A program that ends while every package came within
  // the timeout fails at once.
  vector6d_t q0{};
  double ts0 = 0.0;
  std::vector<double> ts_log, q5_log;  // for the tracking check: controller time, wrist 3
  for (int attempt = 1;; attempt++) {
    while (!rd.read()) {
    }
    q0 = rd.q;
    ts0 = rd.timestamp;
    long cycles = 0, write_failures = 0;
    double max_gap = 0.0, last_ts = rd.timestamp, max_lag_err = 0.0;
    bool dropped = false;
    vector6d_t target = q0;
    ts_log.clear();
    q5_log.clear();
    ts_log.reserve(static_cast<size_t>(servo_seconds * 1000.0) + 16);
    q5_log.reserve(ts_log.capacity());
    const auto t_servo = Clock::now();
    const int drops_before = g_program_drops.load();
    while (rd.timestamp - ts0 < servo_seconds) {
      if (seconds_since(t_servo) > 3.0 * servo_seconds + 10.0) {
        fail("servo phase: the controller clock did not advance");
      }
      if (!rd.read()) {
        continue;
      }
      if (rd.runtime_state != kPlaying || g_program_drops.load() != drops_before) {
        dropped = true;
        break;
      }
      max_gap = std::max(max_gap, rd.timestamp - last_ts);
      last_ts = rd.timestamp;
      // |actual − the target written one cycle ago|: bounded by the servo's lag, no runaway
      max_lag_err = std::max(max_lag_err, std::fabs(rd.q[5] - target[5]));
      const double t = rd.timestamp - ts0;
      ts_log.push_back(t);
      q5_log.push_back(rd.q[5]);
      target = q0;
      target[5] = sine(q0[5], t);
      if (!driver.writeJointCommand(target, comm::ControlMode::MODE_SERVOJ,
                                    RobotReceiveTimeout::millisec(timeout_ms))) {
        write_failures++;
        dropped = true;
        break;
      }
      cycles++;
    }
    std::printf("servo (attempt %d): %ld cycles over %.3f s of controller time at %.0f Hz, %ld "
                "write failures, %ld RTDE misses, largest package gap %.1f ms, program %s, max "
                "|q5 - previous target| %.4f rad\n",
                attempt, cycles, rd.timestamp - ts0, rate, write_failures, rd.missed,
                1e3 * max_gap, dropped ? "stopped" : "played throughout", max_lag_err);
    if (!dropped) {
      break;
    }
    if (!held_back(max_gap, timeout_ms, rate)) {
      fail("servo phase: the program stopped although every package came well within the timeout");
    }
    if (attempt == kAttempts) {
      fail("servo phase: the client was held back past the receive timeout in every attempt");
    }
    std::printf("servo (attempt %d): this client went %.1f ms without a package, past the %u ms "
                "receive timeout: the program ended as on a controller; resending it\n",
                attempt, 1e3 * max_gap, timeout_ms);
    resend_program(driver, rd, "servo phase");
  }

  // ---- 2. a 3-point cubic spline on the trajectory socket, as the passthrough controller -----
  // The same rule as the servo phase: an attempt whose program ended because this client went
  // about the receive timeout without a package is started again with the program resent.
  for (int attempt = 1;; attempt++) {
    const Phase phase = spline_phase(driver, rd, timeout_ms);
    std::printf("trajectory (attempt %d): result %s after %.3f s of controller time (points at "
                "1, 2, 3 s), end error %.2e rad, largest package gap %.1f ms, program %s\n",
                attempt,
                phase.result == -2 ? "none"
                                   : control::trajectoryResultToString(
                                         static_cast<control::TrajectoryResult>(phase.result))
                                         .c_str(),
                phase.took, phase.end_err, 1e3 * phase.max_gap,
                phase.dropped ? "stopped" : "played throughout");
    if (!phase.dropped) {
      if (phase.result != static_cast<int>(control::TrajectoryResult::TRAJECTORY_RESULT_SUCCESS)) {
        fail("trajectory: the result is not TRAJECTORY_RESULT_SUCCESS");
      }
      if (phase.end_err > 1e-3) {
        fail("trajectory: the arm did not end on the last point");
      }
      break;
    }
    if (!held_back(phase.max_gap, timeout_ms, rate)) {
      fail("trajectory: the program stopped although every package came well within the timeout");
    }
    if (attempt == kAttempts) {
      fail("trajectory: the client was held back past the receive timeout in every attempt");
    }
    std::printf("trajectory (attempt %d): this client went %.1f ms without a package, past the "
                "%u ms receive timeout: the program ended as on a controller; resending it\n",
                attempt, 1e3 * phase.max_gap, timeout_ms);
    resend_program(driver, rd, "trajectory");
  }

  // ---- 3. no more writes: the program ends by its receive timeout --------------------------
  const double ts_last_write = rd.timestamp;
  double ts_stopped = -1.0;
  while (ts_stopped < 0.0) {
    if (rd.read() && rd.runtime_state != kPlaying) {
      ts_stopped = rd.timestamp;
    }
    if (rd.timestamp - ts_last_write > 5.0) {
      fail("stop: the program still plays 5 s after the last write");
    }
  }
  const auto t_wait = Clock::now();
  while (driver.isReverseInterfaceConnected() || g_program_running.load()) {
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
    if (seconds_since(t_wait) > 5.0) {
      fail("stop: the reverse socket is still open 5 s after the program stopped");
    }
  }
  std::printf("stop: the program left PLAYING %.0f ms of controller time after the last write "
              "(receive timeout %u ms); reverse socket closed\n",
              1e3 * (ts_stopped - ts_last_write), timeout_ms);
  if (ts_stopped - ts_last_write < 1e-3 * timeout_ms - 1e-9) {
    fail("stop: the program stopped before its receive timeout ran out");
  }
  // Tracking (issue 9: asserted, not printed), judged here at the end: between the servo and
  // the spline phase the driver keeps writing within its receive timeout, and this fit (51 lags
  // over 15 000 samples, each a sin) took longer than the 10 ms on this VM, so the program ended
  // by its timeout before TRAJECTORY_START. The arm follows the commanded sine one lookahead
  // time late (servoj's lookahead 0.03 s, plus the tick that carries the command), and what is
  // left after removing that lag is small. The command is a function of the controller time of
  // the package it answers, so the comparison needs no clock of ours. The first second (the
  // servo taking hold) is left out.
  int best_lag = -1;
  double best_rms = 1e9, best_max = 0.0;
  const double tick = 1.0 / rate;
  for (int lag = 0; lag <= 50; lag++) {
    double sum = 0.0, mx = 0.0;
    long n = 0;
    for (size_t k = 0; k < ts_log.size(); k++) {
      if (ts_log[k] < 1.0) {
        continue;
      }
      const double e = q5_log[k] - sine(q0[5], ts_log[k] - lag * tick);
      sum += e * e;
      mx = std::max(mx, std::fabs(e));
      n++;
    }
    const double rms = n > 0 ? std::sqrt(sum / n) : 1e9;
    if (rms < best_rms) {
      best_rms = rms, best_max = mx, best_lag = lag;
    }
  }
  const double lag_s = best_lag * tick;
  std::printf("tracking: lag %.1f ms (lookahead 30 ms), residual rms %.2e max %.2e rad\n",
              1e3 * lag_s, best_rms, best_max);
  if (std::fabs(lag_s - cfg.servoj_lookahead_time) > 0.004 + 1e-9 || best_max > 1e-3) {
    fail("tracking: the lag is not the lookahead time within 4 ms, or the residual exceeds 1e-3 rad");
  }
  std::printf("ros2_driver_pattern: OK\n");
  return 0;
}
