# ROS-free simulator: device models, line emulation on a pty, executable.
