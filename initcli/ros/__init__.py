"""ROS without ROS: bags in (:mod:`initcli.ros.bag_reader`, its topics chosen in
:mod:`initcli.ros.bag_topics`; a bag as a detection log in :mod:`initcli.ros.convert`), bags out
(:mod:`initcli.ros.bag_writer`), the result in Nav2's messages (:mod:`initcli.ros.nav2`) and a live
rosbridge link (:mod:`initcli.ros.rosbridge`, a real robot behind the driver interface in
:mod:`initcli.ros.rosbridge_driver`). Records in :mod:`initcli.ros.records`, message definitions in
:mod:`initcli.ros.msgdefs`, transforms in :mod:`initcli.ros.tf`."""
