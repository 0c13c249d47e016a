// Small helpers shared by the roscpp peers: node start-up, command-line options, output lines.
//
// Every peer talks to its caller through stdout, one line per event, flushed at once so a test
// reading the pipe sees it immediately. roscpp's own logging (ROS_INFO ...) would also go to
// stdout, so the peers never use it; diagnostics go to stderr.
#pragma once

#include <ros/callback_queue.h>
#include <ros/ros.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <map>
#include <set>
#include <string>
#include <vector>

namespace peer {

using Clock = std::chrono::steady_clock;

// Seconds between two steady-clock instants.
inline double seconds(Clock::time_point from, Clock::time_point to) {
  return std::chrono::duration<double>(to - from).count();
}

// Seconds since the Unix epoch (wall clock), for lining up two processes' timelines.
inline double epoch_now() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

// Print one line on stdout and flush it.
inline void say(const std::string& line) { std::cout << line << '\n' << std::flush; }

// A one-line JSON object built field by field: {"published": 2000, "rate": 1000.0, ...}.
class Json {
 public:
  Json& add(const std::string& key, double value) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.9g", value);
    return raw(key, buf);
  }
  // Seconds since the epoch, to the microsecond (%.9g would round them to seconds).
  Json& add_epoch(const std::string& key, double value) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6f", value);
    return raw(key, buf);
  }
  Json& add(const std::string& key, uint64_t value) { return raw(key, std::to_string(value)); }
  Json& add(const std::string& key, bool value) { return raw(key, value ? "true" : "false"); }
  Json& add(const std::string& key, const std::string& value) {
    std::string quoted = "\"";
    for (char c : value) {
      if (c == '"' || c == '\\') quoted += '\\';
      quoted += c;
    }
    return raw(key, quoted + "\"");
  }
  std::string str() const { return "{" + body_ + "}"; }

 private:
  Json& raw(const std::string& key, const std::string& value) {
    if (!body_.empty()) body_ += ", ";
    body_ += "\"" + key + "\": " + value;
    return *this;
  }
  std::string body_;
};

// ros::init with a node name from "--name NAME" (or `fallback`), anonymous with "--anonymous".
// Run before Args: ros::init removes the ROS remapping arguments (name:=value) from argv, and
// "__name:=NAME" still works as with any ROS node.
inline void init(int& argc, char** argv, const std::string& fallback) {
  std::string name = fallback;
  uint32_t options = 0;
  for (int i = 1; i < argc; ++i) {
    std::string arg = argv[i];
    if (arg == "--name" && i + 1 < argc) name = argv[i + 1];
    if (arg == "--anonymous") options |= ros::init_options::AnonymousName;
  }
  ros::init(argc, argv, name, options);
}

// Positional arguments and --options. An option named in `flags` takes no value; any other
// option named in `options` takes the next argument. Anything else is a usage error (exit 2).
class Args {
 public:
  Args(int argc, char** argv, const std::string& usage, const std::set<std::string>& flags,
       const std::set<std::string>& options)
      : usage_(usage) {
    std::set<std::string> known_flags = flags;
    known_flags.insert("--anonymous");
    std::set<std::string> known_options = options;
    known_options.insert("--name");
    for (int i = 1; i < argc; ++i) {
      std::string arg = argv[i];
      if (arg == "-h" || arg == "--help") {
        std::cout << usage_ << std::endl;
        std::exit(0);
      }
      if (known_flags.count(arg)) {
        values_[arg] = "1";
      } else if (known_options.count(arg)) {
        if (i + 1 >= argc) fail(arg + " needs a value");
        values_[arg] = argv[++i];
      } else if (arg.size() > 2 && arg.compare(0, 2, "--") == 0) {
        fail("unknown option " + arg);
      } else {
        positional_.push_back(arg);
      }
    }
  }

  [[noreturn]] void fail(const std::string& why) const {
    std::cerr << why << "\nusage: " << usage_ << std::endl;
    std::exit(2);
  }

  bool flag(const std::string& name) const { return values_.count(name) > 0; }

  std::string text(const std::string& name, const std::string& fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : it->second;
  }

  double number(const std::string& name, double fallback) const {
    auto it = values_.find(name);
    return it == values_.end() ? fallback : parse_number(it->second);
  }

  // The i-th positional argument; `fallback` when absent (nullptr: required).
  std::string positional(size_t i, const char* fallback = nullptr) const {
    if (i < positional_.size()) return positional_[i];
    if (fallback == nullptr) fail("missing argument " + std::to_string(i + 1));
    return fallback;
  }

  double positional_number(size_t i, const char* fallback = nullptr) const {
    return parse_number(positional(i, fallback));
  }

  size_t positional_count() const { return positional_.size(); }

 private:
  double parse_number(const std::string& text) const {
    char* end = nullptr;
    double value = std::strtod(text.c_str(), &end);
    if (text.empty() || *end != '\0') fail("not a number: " + text);
    return value;
  }

  std::string usage_;
  std::map<std::string, std::string> values_;
  std::vector<std::string> positional_;
};

}  // namespace peer
