// add_two_ints_server: the roscpp AddTwoInts server of the ROS tutorials (rospy_tutorials/AddTwoInts).
//
// usage: add_two_ints_server [SERVICE=/add_two_ints] [--mode ok|fail|throw]
//                            [--name NAME=add_two_ints_server] [--anonymous]
//   --mode ok     answer sum = a + b (default)
//   --mode fail   the callback returns false: roscpp answers ok=0 with an empty error text
//   --mode throw  the callback throws std::runtime_error: roscpp answers ok=0 with its text
// stdout: "ready" once advertised, then "request A B" for every call.
#include <stdexcept>

#include "add_two_ints.h"
#include "peer.h"

namespace {

std::string mode = "ok";

bool add(rospy_tutorials::AddTwoInts::Request& req, rospy_tutorials::AddTwoInts::Response& res) {
  peer::say("request " + std::to_string(req.a) + " " + std::to_string(req.b));
  if (mode == "fail") return false;
  if (mode == "throw") throw std::runtime_error("add_two_ints_server was told to throw");
  // Wrap around on overflow as int64 arithmetic does in Python's struct packing, without UB.
  res.sum = int64_t(uint64_t(req.a) + uint64_t(req.b));
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  peer::init(argc, argv, "add_two_ints_server");
  peer::Args args(argc, argv,
                  "add_two_ints_server [SERVICE=/add_two_ints] [--mode ok|fail|throw] "
                  "[--name NAME] [--anonymous]",
                  {}, {"--mode"});
  const std::string service = args.positional(0, "/add_two_ints");
  mode = args.text("--mode", "ok");
  if (mode != "ok" && mode != "fail" && mode != "throw") args.fail("unknown --mode " + mode);

  ros::NodeHandle nh;
  ros::ServiceServer server = nh.advertiseService(service, add);
  peer::say("ready");
  ros::spin();
  return 0;
}
