// A consumer of octomap_msgs/Octomap, written as a user of that package writes one: it knows the
// message only by its octomap_msgs name and reads the tree with liboctomap. The rostest
// octomap_msgs_interop runs it against the MapServer's octomap_binary topic, whose type is
// occupancy_fusion/Octomap: roscpp connects the two only when their MD5 sums are equal.
//
//   octomap_consumer --md5
//       prints "datatype: ..." and "md5sum: ..." of octomap_msgs/Octomap as compiled here.
//   octomap_consumer OUTPUT.bt [TIMEOUT_SECONDS] [ROS remappings, e.g. octomap_binary:=/map]
//       waits for one message on octomap_binary, decodes its tree, writes it to OUTPUT.bt
//       (liboctomap's writeBinary: maximum likelihood, pruned, as octomap_saver writes) and prints
//       "key: value" lines about the message and its publisher.
// Exit status: 0 done; 1 no message within the timeout (default 20 s of wall time); 2 the
// message could not be decoded or the file not written; 3 bad arguments.
#include <cstdlib>
#include <iostream>
#include <map>
#include <memory>
#include <sstream>
#include <string>

#include <octomap/AbstractOcTree.h>
#include <octomap/AbstractOccupancyOcTree.h>
#include <octomap/OcTree.h>
#include <octomap_msgs/Octomap.h>
#include <ros/ros.h>

namespace {

constexpr int kNoMessage = 1;
constexpr int kDecodeFailed = 2;
constexpr int kUsage = 3;

// The first message and the connection header of its publisher (type, md5sum, callerid).
struct Receiver {
  void onMessage(const ros::MessageEvent<const octomap_msgs::Octomap>& event) {
    if (message) return;
    message = event.getConstMessage();
    connection_header = event.getConnectionHeader();
  }
  octomap_msgs::Octomap::ConstPtr message;
  std::map<std::string, std::string> connection_header;
};

// The type under which the master lists `topic`, or "" when nobody advertises it.
std::string advertisedType(const std::string& topic) {
  ros::master::V_TopicInfo topics;
  if (!ros::master::getTopics(topics)) return "";
  for (const ros::master::TopicInfo& info : topics) {
    if (info.name == topic) return info.datatype;
  }
  return "";
}

// The tree of a message, as octomap_msgs' conversions read it: the tree class named by `id`,
// created by liboctomap's registry, then its binary (labels) or full (log-odds) data.
std::unique_ptr<octomap::AbstractOccupancyOcTree> decode(const octomap_msgs::Octomap& message,
                                                         std::string* error) {
  std::unique_ptr<octomap::AbstractOcTree> tree(
      octomap::AbstractOcTree::createTree(message.id, message.resolution));
  auto* occupancy = dynamic_cast<octomap::AbstractOccupancyOcTree*>(tree.get());
  if (occupancy == nullptr) {
    *error = "liboctomap has no occupancy tree class \"" + message.id + "\"";
    return nullptr;
  }
  tree.release();
  std::unique_ptr<octomap::AbstractOccupancyOcTree> result(occupancy);
  std::stringstream data;
  data.write(reinterpret_cast<const char*>(message.data.data()),
             static_cast<std::streamsize>(message.data.size()));
  if (message.binary) {
    result->readBinaryData(data);
  } else {
    result->readData(data);
  }
  if (!data) {
    *error = "the data ended inside the tree";
    return nullptr;
  }
  if (data.peek() != std::char_traits<char>::eof()) {
    *error = "bytes left over after the tree";
    return nullptr;
  }
  return result;
}

}  // namespace

int main(int argc, char** argv) {
  using Traits = ros::message_traits::MD5Sum<octomap_msgs::Octomap>;
  const std::string datatype = ros::message_traits::DataType<octomap_msgs::Octomap>::value();
  if (argc == 2 && std::string(argv[1]) == "--md5") {
    std::cout << "datatype: " << datatype << "\nmd5sum: " << Traits::value() << std::endl;
    return 0;
  }
  ros::init(argc, argv, "octomap_consumer", ros::init_options::AnonymousName);
  // ros::init removed the remappings: what is left is ours.
  if (argc < 2 || argc > 3) {
    std::cerr << "usage: octomap_consumer --md5 | OUTPUT.bt [TIMEOUT_SECONDS] [remappings]\n";
    return kUsage;
  }
  const std::string output = argv[1];
  const double timeout = argc == 3 ? std::atof(argv[2]) : 20.0;
  if (!(timeout > 0.0)) {
    std::cerr << "TIMEOUT_SECONDS must be a positive number, got " << argv[2] << "\n";
    return kUsage;
  }

  ros::NodeHandle node_handle;
  Receiver received;
  const ros::Subscriber subscriber =
      node_handle.subscribe("octomap_binary", 1, &Receiver::onMessage, &received);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(timeout);
  while (ros::ok() && !received.message && ros::WallTime::now() < deadline) {
    ros::spinOnce();
    ros::WallDuration(0.01).sleep();
  }
  const std::string topic = subscriber.getTopic();
  if (!received.message) {
    const std::string advertised = advertisedType(topic);
    std::cerr << "no message on " << topic << " within " << timeout << " s. This node subscribes "
              << "as " << datatype << " (MD5 " << Traits::value() << "); the topic is "
              << (advertised.empty() ? "not advertised" : "advertised as " + advertised)
              << ", with " << subscriber.getNumPublishers() << " connected publishers. roscpp "
              << "refuses a connection whose MD5 sums differ (the publisher logs the mismatch)."
              << std::endl;
    return kNoMessage;
  }

  const octomap_msgs::Octomap& message = *received.message;
  std::string error;
  const std::unique_ptr<octomap::AbstractOccupancyOcTree> tree = decode(message, &error);
  if (!tree) {
    std::cerr << "cannot decode the tree of the message on " << topic << ": " << error << std::endl;
    return kDecodeFailed;
  }
  const std::size_t decoded_nodes = tree->size();
  if (!tree->writeBinary(output)) {
    std::cerr << "cannot write " << output << std::endl;
    return kDecodeFailed;
  }
  std::cout << "topic: " << topic << "\n"
            << "datatype: " << datatype << "\n"
            << "md5sum: " << Traits::value() << "\n"
            << "publisher_type: " << received.connection_header["type"] << "\n"
            << "publisher_md5sum: " << received.connection_header["md5sum"] << "\n"
            << "frame_id: " << message.header.frame_id << "\n"
            << "binary: " << (message.binary ? "true" : "false") << "\n"
            << "id: " << message.id << "\n"
            << "resolution: " << message.resolution << "\n"
            << "data_bytes: " << message.data.size() << "\n"
            << "decoded_nodes: " << decoded_nodes << "\n"
            << "written: " << output << std::endl;
  return 0;
}
