# Included by the top-level CMakeLists.txt when OBJMAP_WITH_ROS is AUTO or ON. Sets
# OBJMAP_ROS_ENABLED and, when ROS is there, generates the messages and services, declares the
# catkin packages objmap and objmap_msgs (so that other catkin packages find the messages) and adds the ROS folders.
set(OBJMAP_ROS_COMPONENTS roscpp message_generation message_runtime message_filters std_msgs
  geometry_msgs sensor_msgs visualization_msgs nav_msgs tf2 tf2_ros tf2_msgs rosbag rosbag_storage)

# catkin, genmsg and the ROS CMake configs run Python modules that Debian installs for its own
# python3; a pyenv (or virtualenv) python3 first on PATH lacks them. Both variables default to
# the system interpreter unless the caller chose one.
if(NOT DEFINED PYTHON_EXECUTABLE AND EXISTS /usr/bin/python3)
  set(PYTHON_EXECUTABLE /usr/bin/python3 CACHE FILEPATH "Python for catkin and genmsg")
endif()
if(NOT DEFINED Python3_EXECUTABLE AND DEFINED PYTHON_EXECUTABLE)
  set(Python3_EXECUTABLE ${PYTHON_EXECUTABLE} CACHE FILEPATH "Python for the ROS CMake configs")
endif()

# catkin would install its setup files (setup.bash, _setup_util.py, the .catkin marker) with
# absolute destinations under the CMAKE_INSTALL_PREFIX of configure time, so that `cmake
# --install build --prefix P` wrote them outside P (into /usr/local by default).
# cmake/objmap_install.cmake installs them under the prefix of install time instead.
set(CATKIN_INSTALL_INTO_PREFIX_ROOT FALSE)
# objmap's tests start their own rosmaster (tests/ros_node); catkin's test set-up would add a
# second GoogleTest build beside the one tests/ finds.
set(CATKIN_ENABLE_TESTING OFF CACHE BOOL "catkin's own test targets (objmap does not use them)")
find_package(catkin QUIET COMPONENTS ${OBJMAP_ROS_COMPONENTS})
set(_objmap_ros_missing "")
if(NOT catkin_FOUND)
  set(_objmap_ros_missing catkin)
else()
  foreach(component ${OBJMAP_ROS_COMPONENTS})
    if(NOT ${component}_FOUND)
      list(APPEND _objmap_ros_missing ${component})
    endif()
  endforeach()
endif()
if(_objmap_ros_missing)
  if(OBJMAP_WITH_ROS STREQUAL "ON")
    message(FATAL_ERROR "OBJMAP_WITH_ROS=ON but these ROS packages are missing: "
      "${_objmap_ros_missing} (bash scripts/setup.sh installs them)")
  endif()
  message(STATUS "objmap: ROS node not built (missing: ${_objmap_ros_missing})")
  return()
endif()
set(OBJMAP_ROS_ENABLED ON)

add_subdirectory(proto_srv/ros_msgs)
catkin_package(CATKIN_DEPENDS roscpp std_msgs geometry_msgs sensor_msgs visualization_msgs nav_msgs
  message_filters tf2_ros rosbag)

# What every ROS target of objmap compiles and links against: the ROS headers and libraries and
# the generated <objmap_msgs/*.h> message headers.
add_library(objmap_ros_interfaces INTERFACE)
target_include_directories(objmap_ros_interfaces SYSTEM INTERFACE ${catkin_INCLUDE_DIRS}
  ${CATKIN_DEVEL_PREFIX}/${CATKIN_GLOBAL_INCLUDE_DESTINATION})
target_link_libraries(objmap_ros_interfaces INTERFACE ${catkin_LIBRARIES})
add_dependencies(objmap_ros_interfaces objmap_msgs_generate_messages_cpp)

foreach(folder server/ros_bridge server/rosbag_input server/ros_node server/ros_player)
  if(EXISTS ${PROJECT_SOURCE_DIR}/${folder}/CMakeLists.txt)
    add_subdirectory(${folder})
  endif()
endforeach()

# `objmap map file.bag`: the CLI (client/cli, configured before this file, when no ROS target
# existed yet) gets its bag branch here, once objmap_rosbag_input does. Without ROS this block
# is never reached and the CLI answers `.bag` paths with "built without ROS".
if(TARGET objmap AND TARGET objmap_rosbag_input)
  target_sources(objmap PRIVATE ${PROJECT_SOURCE_DIR}/client/cli/map_inputs_rosbag.cc)
  target_link_libraries(objmap PRIVATE objmap_rosbag_input)
  target_compile_definitions(objmap PRIVATE OBJMAP_CLI_WITH_ROSBAG)
endif()

# Executables above go to the devel space (devel/lib/objmap, where rosrun and roslaunch find
# them); the tests and benchmarks that follow keep the usual build tree layout.
unset(CMAKE_ARCHIVE_OUTPUT_DIRECTORY)
unset(CMAKE_LIBRARY_OUTPUT_DIRECTORY)
unset(CMAKE_RUNTIME_OUTPUT_DIRECTORY)
