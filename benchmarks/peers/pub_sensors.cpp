// pub_sensors: a roscpp publisher of a camera's images or a lidar's point clouds at a steady
// rate, each stamped with the wall-clock time of its publish, for benchmarks/bench_bridge.py.
//
// usage: pub_sensors TOPIC KIND RATE [--size BYTES] [--width W --height H] [--rgb8]
//                    [--points N] [--rgb] [--queue Q] [--name NAME]
//   KIND      image (sensor_msgs/Image, mono8, one row of --size pixels, default 1,000,000;
//             --width and --height: that shape instead; --rgb8: 3 bytes a pixel) or
//             cloud (sensor_msgs/PointCloud2 of --points points of x, y, z, intensity as
//             float32: 16 bytes a point, default 1,000,000; --rgb: the fourth field is rgb,
//             a packed colour as PCL writes it)
//   RATE      messages per second (> 0), held on average until SIGINT
//   --queue   the publisher's queue per subscriber (default 4: a slow subscriber loses
//             messages instead of holding gigabytes in this process)
// stdout: "ready" once advertised.
//
// header.stamp is ros::Time::now() (the wall clock, as every peer here runs without sim time)
// taken just before each publish; it sits at bytes 4..12 of the serialised message (after
// header.seq), so a receiver reads the publish time from the payload without decoding it.
// Message k is due k / RATE seconds after the start against a steady clock, as in pub_rate.
#include <sensor_msgs/Image.h>
#include <sensor_msgs/PointCloud2.h>

#include <algorithm>
#include <thread>

#include "peer.h"

namespace {

template <class M>
void run(ros::Publisher& pub, M& msg, double rate) {
  uint64_t sent = 0;
  const auto start = peer::Clock::now();
  while (ros::ok()) {
    const double elapsed = peer::seconds(start, peer::Clock::now());
    const auto due = uint64_t(elapsed * rate) + 1;
    while (sent < due && ros::ok()) {
      msg.header.stamp = ros::Time::now();
      pub.publish(msg);
      ++sent;
    }
    const double wait = double(sent) / rate - peer::seconds(start, peer::Clock::now());
    if (wait > 0) {
      std::this_thread::sleep_for(std::chrono::duration<double>(std::clamp(wait, 100e-6, 1e-3)));
    }
  }
}

sensor_msgs::PointField field(const std::string& name, uint32_t offset) {
  sensor_msgs::PointField f;
  f.name = name;
  f.offset = offset;
  f.datatype = sensor_msgs::PointField::FLOAT32;
  f.count = 1;
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  peer::init(argc, argv, "pub_sensors");
  peer::Args args(argc, argv,
                  "pub_sensors TOPIC KIND RATE [--size BYTES] [--width W --height H] [--rgb8] "
                  "[--points N] [--rgb] [--queue Q] [--name NAME]",
                  {"--rgb8", "--rgb"}, {"--size", "--width", "--height", "--points", "--queue"});
  const std::string topic = args.positional(0);
  const std::string kind = args.positional(1);
  const double rate = args.positional_number(2);
  const auto queue = uint32_t(args.number("--queue", 4));
  if (rate <= 0) args.fail("RATE must be > 0");
  if (kind != "image" && kind != "cloud") args.fail("KIND must be image or cloud, not " + kind);

  ros::NodeHandle nh;
  ros::Publisher pub;
  sensor_msgs::Image image;
  sensor_msgs::PointCloud2 cloud;
  if (kind == "image") {
    const auto size = uint32_t(args.number("--size", 1000000));
    const uint32_t channels = args.flag("--rgb8") ? 3 : 1;
    image.header.frame_id = "camera";
    image.height = uint32_t(args.number("--height", 1));
    image.width = uint32_t(args.number("--width", size));
    image.encoding = channels == 3 ? "rgb8" : "mono8";
    image.step = image.width * channels;
    image.data.assign(size_t(image.step) * image.height, 0x5a);
    pub = nh.advertise<sensor_msgs::Image>(topic, queue);
  } else {
    const auto points = uint32_t(args.number("--points", 1000000));
    cloud.header.frame_id = "lidar";
    cloud.height = 1;
    cloud.width = points;
    cloud.fields = {field("x", 0), field("y", 4), field("z", 8), field(args.flag("--rgb") ? "rgb" : "intensity", 12)};
    cloud.point_step = 16;
    cloud.row_step = 16 * points;
    cloud.is_dense = true;
    cloud.data.assign(size_t(16) * points, 0x3c);
    pub = nh.advertise<sensor_msgs::PointCloud2>(topic, queue);
  }
  peer::say("ready");
  if (kind == "image") {
    run(pub, image, rate);
  } else {
    run(pub, cloud, rate);
  }
  return 0;
}
