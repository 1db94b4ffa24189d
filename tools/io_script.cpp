// SPDX-License-Identifier: Apache-2.0
// tools/io_script.cpp — `urtwin --io FILE` (io_script.h).
#include "io_script.h"

#include <yaml-cpp/yaml.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <thread>

namespace {

int line_of(const YAML::Node &n) { return n.Mark().line >= 0 ? n.Mark().line + 1 : 1; }

struct Fail {
  int line;
  std::string key, reason;
};

// One group of pins: "standard_digital_in: {0: true}" → bits base + pin.
void digital(const YAML::Node &map, const std::string &key, int base, int pins,
             urt_ctrl_cmd_t *c) {
  if (!map.IsMap()) {
    throw Fail{line_of(map), key, "expected a map of pin: true|false"};
  }
  for (const auto &kv : map) {
    int pin;
    bool level;
    if (!YAML::convert<int>::decode(kv.first, pin) || pin < 0 || pin >= pins) {
      throw Fail{line_of(kv.first), key,
                 "pin '" + kv.first.Scalar() + "': expected 0.." + std::to_string(pins - 1)};
    }
    const std::string v = kv.second.IsScalar() ? kv.second.Scalar() : "";
    if (v == "true") {
      level = true;
    } else if (v == "false") {
      level = false;
    } else {
      throw Fail{line_of(kv.second), key + "." + std::to_string(pin),
                 "expected true or false, got '" + v + "'"};
    }
    const uint32_t bit = 1u << (base + pin);
    c->index = static_cast<int32_t>(static_cast<uint32_t>(c->index) | bit);
    c->value = static_cast<double>((static_cast<uint32_t>(c->value) & ~bit) | (level ? bit : 0u));
  }
}

void analog(const YAML::Node &map, const std::string &key, int first, urt_ctrl_cmd_t *c) {
  if (!map.IsMap()) {
    throw Fail{line_of(map), key, "expected a map of input: volts"};
  }
  for (const auto &kv : map) {
    int k;
    double v;
    if (!YAML::convert<int>::decode(kv.first, k) || k < 0 || k > 1) {
      throw Fail{line_of(kv.first), key, "input '" + kv.first.Scalar() + "': expected 0 or 1"};
    }
    const std::string item = key + "." + std::to_string(k);
    if (!kv.second.IsScalar() || !YAML::convert<double>::decode(kv.second, v) ||
        !std::isfinite(v)) {
      throw Fail{line_of(kv.second), item, "expected a number of volts"};
    }
    if (v < 0.0 || v > 10.0) {
      throw Fail{line_of(kv.second), item, "outside [0, 10] V (voltage-mode analog input)"};
    }
    c->q[first + k] = v;
    c->a = static_cast<double>(static_cast<uint32_t>(c->a) | (1u << (first + k)));
  }
}

}  // namespace

bool io_script_load(const std::string &path, std::vector<IoEvent> *out, std::string *err) {
  YAML::Node doc;
  try {
    doc = YAML::LoadFile(path);
  } catch (const YAML::BadFile &) {
    *err = path + ": cannot read: " + std::strerror(errno);
    return false;
  } catch (const YAML::Exception &e) {
    *err = path + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg;
    return false;
  }
  out->clear();
  try {
    if (!doc.IsSequence()) {
      throw Fail{line_of(doc), "(top)", "expected a list of entries (- t: SECONDS ...)"};
    }
    double last_t = 0.0;
    for (const auto &e : doc) {
      if (!e.IsMap()) {
        throw Fail{line_of(e), "(entry)", "expected a map with t and the inputs to change"};
      }
      IoEvent ev{};
      ev.line = line_of(e);
      ev.cmd.kind = URT_CTRL_SET_INPUTS;
      bool has_t = false, has_change = false;
      for (const auto &kv : e) {
        const std::string key = kv.first.Scalar();
        if (key == "t") {
          if (!kv.second.IsScalar() || !YAML::convert<double>::decode(kv.second, ev.t) ||
              !std::isfinite(ev.t) || ev.t < 0.0) {
            throw Fail{line_of(kv.second), "t", "expected seconds >= 0"};
          }
          if (ev.t < last_t) {
            throw Fail{line_of(kv.second), "t", "times must not decrease"};
          }
          has_t = true;
          continue;
        }
        has_change = true;
        if (key == "standard_digital_in") {
          digital(kv.second, key, 0, 8, &ev.cmd);
        } else if (key == "configurable_digital_in") {
          digital(kv.second, key, 8, 8, &ev.cmd);
        } else if (key == "tool_digital_in") {
          digital(kv.second, key, 16, 2, &ev.cmd);
        } else if (key == "standard_analog_in") {
          analog(kv.second, key, 0, &ev.cmd);
        } else if (key == "tool_analog_in") {
          analog(kv.second, key, 2, &ev.cmd);
        } else {
          throw Fail{line_of(kv.first), key,
                     "unknown key (t, standard_digital_in, configurable_digital_in, "
                     "tool_digital_in, standard_analog_in, tool_analog_in)"};
        }
      }
      if (!has_t) {
        throw Fail{ev.line, "t", "missing"};
      }
      if (!has_change) {
        throw Fail{ev.line, "(entry)", "changes no input"};
      }
      last_t = ev.t;
      out->push_back(ev);
    }
  } catch (const Fail &f) {
    *err = path + ":" + std::to_string(f.line) + ": " + f.key + ": " + f.reason;
    out->clear();
    return false;
  }
  return true;
}

struct IoPlayer::Impl {
  urt_loop_t *loop;
  std::vector<IoEvent> events;
  int producer = -1;
  std::atomic<bool> stop{false};
  std::atomic<size_t> played{0}, dropped{0};
  std::thread thread;

  void run() {
    const double period = urt_loop_period(loop);
    uint64_t tick = urt_loop_latest_tick(loop);
    for (const IoEvent &e : events) {
      // the tick whose snapshot first shows the change is the first at or after t
      while (!stop.load() && static_cast<double>(tick + 1) * period < e.t - 1e-12) {
        tick = urt_loop_wait(loop, tick, 50);
      }
      if (stop.load()) {
        return;
      }
      if (urt_loop_submit(loop, producer, &e.cmd)) {
        played++;
      } else {
        dropped++;
      }
    }
  }
};

IoPlayer::IoPlayer(urt_loop_t *loop, std::vector<IoEvent> events) : impl_(new Impl) {
  impl_->loop = loop;
  impl_->events = std::move(events);
}

IoPlayer::~IoPlayer() {
  stop();
  delete impl_;
}

bool IoPlayer::start(std::string *err) {
  impl_->producer = urt_loop_add_producer(impl_->loop, "io");
  if (impl_->producer < 0) {
    *err = "--io: no command ring left for the I/O script";
    return false;
  }
  impl_->thread = std::thread([this] { impl_->run(); });
  return true;
}

void IoPlayer::stop() {
  impl_->stop = true;
  if (impl_->thread.joinable()) {
    impl_->thread.join();
  }
}

size_t IoPlayer::played() const { return impl_->played.load(); }
size_t IoPlayer::dropped() const { return impl_->dropped.load(); }
