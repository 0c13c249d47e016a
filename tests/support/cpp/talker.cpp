// talker: the roscpp talker of the ROS tutorials, publishing std_msgs/String "hello N".
//
// usage: talker [TOPIC=/chatter] [--rate HZ=10] [--count N] [--latch] [--name NAME=talker]
//               [--anonymous]
// stdout: "ready" once advertised, "sent hello N" per message, "done" after --count messages;
// it then stays up (so a latched last message still reaches late subscribers) until SIGINT.
#include <std_msgs/String.h>

#include "peer.h"

int main(int argc, char** argv) {
  peer::init(argc, argv, "talker");
  peer::Args args(argc, argv,
                  "talker [TOPIC=/chatter] [--rate HZ] [--count N] [--latch] [--name NAME] "
                  "[--anonymous]",
                  {"--latch"}, {"--rate", "--count"});
  const std::string topic = args.positional(0, "/chatter");
  const double rate_hz = args.number("--rate", 10);
  const auto count = uint64_t(args.number("--count", 0));
  if (rate_hz <= 0) args.fail("--rate must be positive");

  ros::NodeHandle nh;
  ros::Publisher pub = nh.advertise<std_msgs::String>(topic, 1000, args.flag("--latch"));
  peer::say("ready");
  ros::WallRate rate(rate_hz);
  for (uint64_t n = 0; ros::ok() && (count == 0 || n < count); ++n) {
    std_msgs::String msg;
    msg.data = "hello " + std::to_string(n);
    pub.publish(msg);
    peer::say("sent " + msg.data);
    rate.sleep();
  }
  if (count > 0) peer::say("done");
  ros::waitForShutdown();
  return 0;
}
