// sub_count: a roscpp subscriber that counts messages and bytes, for benchmarks and interop tests.
//
// usage: sub_count TOPIC [--type any|std_msgs/String|sensor_msgs/Image] [--count N]
//                  [--duration S] [--timeout S] [--idle S] [--print] [--tcp-nodelay]
//                  [--queue Q] [--name NAME] [--anonymous]
//   --type      any (default when topic_tools is installed): any type, never deserialized
//               (topic_tools::ShapeShifter); or a concrete type, deserialized per message
//   --count     stop after N messages
//   --duration  stop S seconds after the first message
//   --timeout   stop S seconds after start-up, whatever arrived
//   --idle      stop once no message came for S seconds (after the first)
//   --print     print "got <data>" for every std_msgs/String message
//   --tcp-nodelay  ask the publisher for TCP_NODELAY (ros::TransportHints().tcpNoDelay())
// stdout: "ready" once subscribed, "got <data>" lines with --print, then one JSON line, also on
// SIGINT:
//   {"received": N, "bytes": B, "seconds": S, "rate": R, "bytes_per_second": T, "type": ...,
//    "reason": "count"|"duration"|"timeout"|"idle"|"shutdown", "t_first": epoch s,
//    "t_last": epoch s}
// where S runs from the first message's callback to the last, R = (N - 1) / S (as `rostopic hz`
// computes it) and T = R * B / N; bytes are serialized message bytes, without the 4-byte length.
#include <sensor_msgs/Image.h>
#include <std_msgs/String.h>

#ifndef HAVE_TOPIC_TOOLS  // set by tests/support/cppbuild.py when the header is installed
#define HAVE_TOPIC_TOOLS 0
#endif
#if HAVE_TOPIC_TOOLS
#include <topic_tools/shape_shifter.h>
#endif

#include "peer.h"

namespace {

// What has arrived so far; only touched on the main thread, which runs the callbacks.
struct Tally {
  uint64_t received = 0;
  uint64_t bytes = 0;
  peer::Clock::time_point first, last;
  double t_first = 0;
  bool print = false;
  uint64_t limit = 0;  // --count; 0 for none

  // Whether the message is counted: callAvailable runs every queued callback at once, and
  // those past --count must not be.
  bool count(uint64_t size) {
    if (limit > 0 && received >= limit) return false;
    last = peer::Clock::now();
    if (received == 0) {
      first = last;
      t_first = peer::epoch_now();
    }
    ++received;
    bytes += size;
    return true;
  }
};

Tally tally;
std::string seen_type;

template <class M>
void on_typed(const boost::shared_ptr<const M>& msg) {
  tally.count(ros::serialization::serializationLength(*msg));
}

void on_string(const std_msgs::String::ConstPtr& msg) {
  if (tally.count(ros::serialization::serializationLength(*msg)) && tally.print) {
    peer::say("got " + msg->data);
  }
}

#if HAVE_TOPIC_TOOLS
void on_any(const topic_tools::ShapeShifter::ConstPtr& msg) {
  seen_type = msg->getDataType();
  if (tally.count(msg->size()) && tally.print && seen_type == "std_msgs/String") {
    peer::say("got " + msg->instantiate<std_msgs::String>()->data);
  }
}
#endif

}  // namespace

int main(int argc, char** argv) {
  peer::init(argc, argv, "sub_count");
  peer::Args args(argc, argv,
                  "sub_count TOPIC [--type any|std_msgs/String|sensor_msgs/Image] [--count N] "
                  "[--duration S] [--timeout S] [--idle S] [--print] [--tcp-nodelay] "
                  "[--queue Q] [--name NAME] [--anonymous]",
                  {"--print", "--tcp-nodelay"},
                  {"--type", "--count", "--duration", "--timeout", "--idle", "--queue"});
  const std::string topic = args.positional(0);
  const std::string type = args.text("--type", HAVE_TOPIC_TOOLS ? "any" : "std_msgs/String");
  const auto count = uint64_t(args.number("--count", 0));
  const double duration = args.number("--duration", 0);
  const double timeout = args.number("--timeout", 0);
  const double idle = args.number("--idle", 0);
  // A deep callback queue: the subscriber drops the oldest message when it overflows, and a
  // benchmark must see the transport's losses, not this program's.
  const auto queue = uint32_t(args.number("--queue", 100000));
  tally.print = args.flag("--print");
  tally.limit = count;
  const auto hints = ros::TransportHints().tcpNoDelay(args.flag("--tcp-nodelay"));
  const std::set<std::string> types = {"std_msgs/String", "sensor_msgs/Image",
                                       HAVE_TOPIC_TOOLS ? "any" : "std_msgs/String"};
  // Before the NodeHandle: its constructor starts the node and would wait for a master.
  if (!types.count(type)) args.fail("unsupported --type " + type);

  ros::NodeHandle nh;
  ros::Subscriber sub;
  if (type == "std_msgs/String") {
    sub = nh.subscribe<std_msgs::String>(topic, queue, on_string, hints);
  } else if (type == "sensor_msgs/Image") {
    sub = nh.subscribe<sensor_msgs::Image>(topic, queue, on_typed<sensor_msgs::Image>, hints);
#if HAVE_TOPIC_TOOLS
  } else if (type == "any") {
    sub = nh.subscribe<topic_tools::ShapeShifter>(topic, queue, on_any, hints);
#endif
  }
  seen_type = type;
  peer::say("ready");

  std::string reason = "shutdown";
  const auto start = peer::Clock::now();
  auto* callbacks = ros::getGlobalCallbackQueue();
  while (ros::ok()) {
    callbacks->callAvailable(ros::WallDuration(0.005));
    const auto now = peer::Clock::now();
    const bool any = tally.received > 0;
    if (count > 0 && tally.received >= count) {
      reason = "count";
    } else if (duration > 0 && any && peer::seconds(tally.first, now) >= duration) {
      reason = "duration";
    } else if (idle > 0 && any && peer::seconds(tally.last, now) >= idle) {
      reason = "idle";
    } else if (timeout > 0 && peer::seconds(start, now) >= timeout) {
      reason = "timeout";
    } else {
      continue;
    }
    break;
  }

  const double span = tally.received > 1 ? peer::seconds(tally.first, tally.last) : 0.0;
  const double rate = span > 0 ? double(tally.received - 1) / span : 0.0;
  const double mean_size = tally.received ? double(tally.bytes) / double(tally.received) : 0.0;
  peer::Json out;
  out.add("received", tally.received)
      .add("bytes", tally.bytes)
      .add("seconds", span)
      .add("rate", rate)
      .add("bytes_per_second", rate * mean_size)
      .add("type", seen_type)
      .add("reason", reason)
      .add_epoch("t_first", tally.t_first)
      .add_epoch("t_last", tally.t_first + span);
  peer::say(out.str());
  return 0;
}
