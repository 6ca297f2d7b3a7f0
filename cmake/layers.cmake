# The ROS-free layer libraries and every library's source list, written once. Included by the
# catkin build (CMakeLists.txt) and by the instrumented builds (test/sanitizers/CMakeLists.txt:
# ASan + UBSan with gcc, or libFuzzer with clang), so a source file in a layer's folder is in
# all of them.
#
# The includer has included cmake/dependencies.cmake (libmodbus, yaml-cpp, Threads, nlohmann_json,
# CLI11; MODBUS_RTU_DIR, the repository's root), and may set:
#   MODBUS_RTU_LIBRARY_TYPE   SHARED in the instrumented builds: device types register through
#                             static initializers in objects nothing references, which a static
#                             archive would leave out of the executable. Unset (catkin): catkin's
#                             default, shared.
#   MODBUS_RTU_ALLOW_UNDEFINED  ON in the fuzz build: clang links its sanitizer runtimes into
#                             executables only, so a library leaves __asan_* undefined and
#                             --no-undefined would fail. The gcc builds keep the rule.
#
# The layers, each a library linked only on the ones below it; --no-undefined makes a call that
# goes the wrong way a link error, and scripts/check_conventions.sh checks the includes:
#   core (ROS-free; five libraries, one per folder of src/core: see below)
#   <- devices (one class per device type) <- failsafe (channel intents) <- node_config (the bus
#   node's YAML; not core/config, the link, slave and signal settings) <- runtime (one bus
#   composed: its devices, fail-safes, trigger clock, start and stop, share)
#   <- ros (adapters, node).   sim and tools sit on core (tools also on devices); simulation
#   (the fail-safe's deterministic simulation) on runtime and sim.
# The executables on these layers: cmake/executables.cmake; the ROS library and the node:
# cmake/ros_node.cmake; the unit tests: cmake/unit_tests.cmake.

# A layer's sources: every .cpp in its folder, the executables' *_main.cpp aside. A new file (a
# device type's class, adapter or simulated device, which registers itself) needs no line here;
# CONFIGURE_DEPENDS makes the build re-run CMake when a file comes or goes.
function(layer_sources out folder)
  file(GLOB sources CONFIGURE_DEPENDS ${MODBUS_RTU_DIR}/src/${folder}/*.cpp)
  list(FILTER sources EXCLUDE REGEX "_main\\.cpp$")
  list(SORT sources)
  set(${out} ${sources} PARENT_SCOPE)
endfunction()

function(layer target)
  if(NOT MODBUS_RTU_ALLOW_UNDEFINED)
    target_link_options(${target} PRIVATE -Wl,--no-undefined)
  endif()
endfunction()

# Core, one library per job, each linked only on the ones before it (the same one-way rule):
#   modbus (framing: ADU, CRC, MBAP, request framer) <- config (link, slave role, share and
#   signal settings and their YAML; the device type descriptors and their registry) <- link (the
#   kinds of link, each registered from its own file, and our own reply reader) <- bus (the bus thread, its queue, rates, real-time) <-
#   server (the slave role, the Modbus TCP server, the share gateway).
# modbus_rtu_core is all five, for the layers above.
set(MODBUS_RTU_CORE_JOBS modbus config link bus server)
set(below "")
foreach(job ${MODBUS_RTU_CORE_JOBS})
  layer_sources(job_sources core/${job})
  add_library(modbus_rtu_core_${job} ${MODBUS_RTU_LIBRARY_TYPE} ${job_sources})
  target_include_directories(modbus_rtu_core_${job} PUBLIC ${MODBUS_RTU_DIR}/include)
  target_link_libraries(modbus_rtu_core_${job} PUBLIC ${below})
  layer(modbus_rtu_core_${job})
  set(below modbus_rtu_core_${job})
endforeach()
# libmodbus opens the serial port and sends (link); yaml-cpp parses the settings (config).
target_include_directories(modbus_rtu_core_link PUBLIC ${LIBMODBUS_INCLUDE_DIRS})
target_link_libraries(modbus_rtu_core_link PUBLIC ${LIBMODBUS_LIBRARIES})
target_link_libraries(modbus_rtu_core_config PUBLIC yaml-cpp)
target_link_libraries(modbus_rtu_core_bus PUBLIC Threads::Threads)
add_library(modbus_rtu_core INTERFACE)
target_link_libraries(modbus_rtu_core INTERFACE ${below})

# Devices: one class per type (each registers itself); merged writes; the fail-safe policy.
layer_sources(devices_sources devices)
add_library(modbus_rtu_devices ${MODBUS_RTU_LIBRARY_TYPE} ${devices_sources})
target_link_libraries(modbus_rtu_devices PUBLIC modbus_rtu_core)
layer(modbus_rtu_devices)

# Fail-safe: what each output channel should show and why (channel intents), ROS-free.
layer_sources(failsafe_sources failsafe)
add_library(modbus_rtu_failsafe ${MODBUS_RTU_LIBRARY_TYPE} ${failsafe_sources})
target_link_libraries(modbus_rtu_failsafe PUBLIC modbus_rtu_devices)
layer(modbus_rtu_failsafe)

# The bus node's configuration: link, devices (checked against their type), fail-safe keys.
layer_sources(node_config_sources node_config)
add_library(modbus_rtu_node_config ${MODBUS_RTU_LIBRARY_TYPE} ${node_config_sources})
target_link_libraries(modbus_rtu_node_config PUBLIC modbus_rtu_failsafe)
layer(modbus_rtu_node_config)

# The bus runtime (ROS-free): the composition root of one bus, which the node and the
# fail-safe's simulation both run.
layer_sources(runtime_sources runtime)
add_library(modbus_rtu_runtime ${MODBUS_RTU_LIBRARY_TYPE} ${runtime_sources})
target_link_libraries(modbus_rtu_runtime PUBLIC modbus_rtu_node_config)
layer(modbus_rtu_runtime)

# Simulator (ROS-free): simulated devices, the line on a pty, fault injection, control socket.
layer_sources(sim_sources sim)
add_library(modbus_rtu_sim ${MODBUS_RTU_LIBRARY_TYPE} ${sim_sources})
target_link_libraries(modbus_rtu_sim PUBLIC modbus_rtu_core yaml-cpp Threads::Threads)
layer(modbus_rtu_sim)

# The fail-safe's deterministic simulation (ROS-free): the node's real parts (devices, fail-safe,
# bus scheduler in step mode) against the simulator's device models in one process, on a manual
# clock; its main (failsafe_simulation_main.cpp) is the includer's.
layer_sources(simulation_sources simulation)
add_library(modbus_rtu_simulation ${MODBUS_RTU_LIBRARY_TYPE} ${simulation_sources})
target_link_libraries(modbus_rtu_simulation PUBLIC modbus_rtu_runtime modbus_rtu_sim)
layer(modbus_rtu_simulation)

# Commissioning tool (ROS-free): a library the unit tests use (its main is the includer's).
layer_sources(tools_sources tools)
add_library(modbus_rtu_commission_lib ${MODBUS_RTU_LIBRARY_TYPE} ${tools_sources})
target_link_libraries(modbus_rtu_commission_lib PUBLIC modbus_rtu_devices nlohmann_json::nlohmann_json
  PRIVATE CLI11::CLI11)
layer(modbus_rtu_commission_lib)
