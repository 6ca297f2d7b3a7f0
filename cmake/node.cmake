# ROS adapters and the node executables.
