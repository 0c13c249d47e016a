// rospy_tutorials/AddTwoInts, written by hand: Debian ships no C++ header for the tutorial
// types. It follows what gencpp generates (see /usr/include/std_srvs/SetBool*.h): plain
// structs, plus the message_traits, service_traits and Serializer specializations roscpp uses
// to advertise, frame and (de)serialize them.
//
//   int64 a
//   int64 b
//   ---
//   int64 sum
#pragma once

#include <ros/builtin_message_traits.h>
#include <ros/message_traits.h>
#include <ros/serialization.h>
#include <ros/service_traits.h>

#include <boost/shared_ptr.hpp>

namespace rospy_tutorials {

struct AddTwoIntsRequest {
  int64_t a = 0;
  int64_t b = 0;
  typedef boost::shared_ptr<AddTwoIntsRequest> Ptr;
  typedef boost::shared_ptr<AddTwoIntsRequest const> ConstPtr;
};

struct AddTwoIntsResponse {
  int64_t sum = 0;
  typedef boost::shared_ptr<AddTwoIntsResponse> Ptr;
  typedef boost::shared_ptr<AddTwoIntsResponse const> ConstPtr;
};

struct AddTwoInts {
  typedef AddTwoIntsRequest Request;
  typedef AddTwoIntsResponse Response;
  Request request;
  Response response;
};

}  // namespace rospy_tutorials

// Defines Trait<T>::value() (and value(const T&)) returning `text`, as gencpp does.
#define ROSTOOLS_TRAIT(trait, T, text)                       \
  template <>                                                \
  struct trait<T> {                                          \
    static const char* value() { return text; }             \
    static const char* value(const T&) { return value(); }   \
  }

namespace ros {
namespace message_traits {

template <> struct IsMessage<rospy_tutorials::AddTwoIntsRequest> : TrueType {};
template <> struct IsMessage<rospy_tutorials::AddTwoIntsResponse> : TrueType {};
template <> struct IsFixedSize<rospy_tutorials::AddTwoIntsRequest> : TrueType {};
template <> struct IsFixedSize<rospy_tutorials::AddTwoIntsResponse> : TrueType {};
template <> struct HasHeader<rospy_tutorials::AddTwoIntsRequest> : FalseType {};
template <> struct HasHeader<rospy_tutorials::AddTwoIntsResponse> : FalseType {};

// md5("int64 a\nint64 b") and md5("int64 sum"): the request and response message md5sums.
ROSTOOLS_TRAIT(MD5Sum, rospy_tutorials::AddTwoIntsRequest, "36d09b846be0b371c5f190354dd3153e");
ROSTOOLS_TRAIT(MD5Sum, rospy_tutorials::AddTwoIntsResponse, "b88405221c77b1878a3cbbfff53428d7");
ROSTOOLS_TRAIT(DataType, rospy_tutorials::AddTwoIntsRequest, "rospy_tutorials/AddTwoIntsRequest");
ROSTOOLS_TRAIT(DataType, rospy_tutorials::AddTwoIntsResponse, "rospy_tutorials/AddTwoIntsResponse");
ROSTOOLS_TRAIT(Definition, rospy_tutorials::AddTwoIntsRequest, "int64 a\nint64 b\n");
ROSTOOLS_TRAIT(Definition, rospy_tutorials::AddTwoIntsResponse, "int64 sum\n");

}  // namespace message_traits

namespace service_traits {

// The service md5sum: md5 of the request text followed by the response text.
#define ROSTOOLS_SERVICE_TRAITS(T)                                      \
  ROSTOOLS_TRAIT(MD5Sum, T, "6a2e34150c00229791cc89ff309fff21");        \
  ROSTOOLS_TRAIT(DataType, T, "rospy_tutorials/AddTwoInts")
ROSTOOLS_SERVICE_TRAITS(rospy_tutorials::AddTwoInts);
ROSTOOLS_SERVICE_TRAITS(rospy_tutorials::AddTwoIntsRequest);
ROSTOOLS_SERVICE_TRAITS(rospy_tutorials::AddTwoIntsResponse);
#undef ROSTOOLS_SERVICE_TRAITS

}  // namespace service_traits

namespace serialization {

template <>
struct Serializer<rospy_tutorials::AddTwoIntsRequest> {
  template <typename Stream, typename T>
  inline static void allInOne(Stream& stream, T m) {
    stream.next(m.a);
    stream.next(m.b);
  }
  ROS_DECLARE_ALLINONE_SERIALIZER
};

template <>
struct Serializer<rospy_tutorials::AddTwoIntsResponse> {
  template <typename Stream, typename T>
  inline static void allInOne(Stream& stream, T m) {
    stream.next(m.sum);
  }
  ROS_DECLARE_ALLINONE_SERIALIZER
};

}  // namespace serialization
}  // namespace ros

#undef ROSTOOLS_TRAIT
