"""ROS without ROS: bags in (:mod:`initcli.ros.bag_reader`), bags out (:mod:`initcli.ros.bag_writer`),
the result in Nav2's messages (:mod:`initcli.ros.nav2`) and a live rosbridge link
(:mod:`initcli.ros.rosbridge`). Records in :mod:`initcli.ros.records`, message definitions in
:mod:`initcli.ros.msgdefs`, transforms in :mod:`initcli.ros.tf`."""
