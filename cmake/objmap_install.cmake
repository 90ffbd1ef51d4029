# `cmake --install build --prefix P`: a working objmap under any prefix.
#   P/bin/                 objmap, objmap_server, objmap_node and objmap_dataset_player (those built)
#   P/share/objmap/        models/centernet_coco.pb, objmap.example.yaml, launch/*.launch,
#                          viewer/ (the web viewer's page and three.js)
#   P/lib/objmap/          links to the ROS executables, where rosrun and roslaunch look
#   P/share/objmap/launch/objmap.rviz, and with ROS: P/share/objmap_msgs (msg, srv), P/include/
#   objmap_msgs, P/lib/python3/dist-packages/objmap_msgs and P/setup.bash, which puts them all
#   on the ROS paths (source P/setup.bash; rosservice, rostopic, rospy, roslaunch)
# The executables find the model relative to their own location (detection/model_location.h),
# so nothing here is configured with P. Included by the top-level CMakeLists.txt after every
# target exists.
include(GNUInstallDirs)
set(OBJMAP_INSTALL_SHARE_DIR ${CMAKE_INSTALL_DATADIR}/objmap)

foreach(program objmap objmap_server objmap_node objmap_dataset_player)
  if(TARGET ${program})
    install(TARGETS ${program} RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
  endif()
endforeach()

# roslaunch's pkg="objmap" looks in lib/objmap (catkin's package executable folder).
foreach(program objmap_node objmap_dataset_player)
  if(TARGET ${program})
    install(CODE "
      set(_link \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/lib/objmap/${program}\")
      file(MAKE_DIRECTORY \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/lib/objmap\")
      file(REMOVE \"\${_link}\")
      file(CREATE_LINK ../../${CMAKE_INSTALL_BINDIR}/${program} \"\${_link}\" SYMBOLIC)
      message(STATUS \"Installing: \${_link} -> ../../${CMAKE_INSTALL_BINDIR}/${program}\")")
  endif()
endforeach()

# The detector model, when scripts/fetch_model.sh has made it; without it the executables say
# where they looked.
set(OBJMAP_MODEL_FILE ${PROJECT_SOURCE_DIR}/models/centernet_coco.pb)
if(NOT EXISTS ${OBJMAP_MODEL_FILE})
  message(STATUS "objmap: ${OBJMAP_MODEL_FILE} is absent (scripts/fetch_model.sh makes it); "
    "the install will not have the detector model")
endif()
install(FILES ${OBJMAP_MODEL_FILE} DESTINATION ${OBJMAP_INSTALL_SHARE_DIR}/models OPTIONAL)

# The web viewer's page, and three.js as scripts/setup.sh installs it from npm (the same layout as
# the source folder, so that the page's import map holds for both).
set(_objmap_web ${PROJECT_SOURCE_DIR}/server/http_viewer/web)
install(FILES ${_objmap_web}/index.html ${_objmap_web}/viewer.js ${_objmap_web}/viewer.css
  DESTINATION ${OBJMAP_INSTALL_SHARE_DIR}/viewer)
if(NOT EXISTS ${_objmap_web}/node_modules/three/build/three.module.js)
  message(STATUS "objmap: three.js is absent from ${_objmap_web}/node_modules (scripts/setup.sh "
    "installs it); the install's viewer will not start")
endif()
install(FILES ${_objmap_web}/node_modules/three/build/three.module.js
  ${_objmap_web}/node_modules/three/build/three.core.js
  DESTINATION ${OBJMAP_INSTALL_SHARE_DIR}/viewer/node_modules/three/build OPTIONAL)
install(FILES ${_objmap_web}/node_modules/three/LICENSE
  DESTINATION ${OBJMAP_INSTALL_SHARE_DIR}/viewer/node_modules/three OPTIONAL)
install(FILES ${_objmap_web}/node_modules/three/examples/jsm/controls/OrbitControls.js
  DESTINATION ${OBJMAP_INSTALL_SHARE_DIR}/viewer/node_modules/three/examples/jsm/controls OPTIONAL)

set(OBJMAP_EXAMPLE_CONFIG ${PROJECT_SOURCE_DIR}/server/core/config/objmap.example.yaml)
install(FILES ${OBJMAP_EXAMPLE_CONFIG} DESTINATION ${OBJMAP_INSTALL_SHARE_DIR})

# The launch files load the example configuration from the source tree's layout
# ($(find objmap) is the source folder in a catkin devel space); the installed copies point to
# the installed one instead. They wait in the build tree as `*.launch.installed`: roslaunch
# resolves `roslaunch objmap NAME.launch` by walking the whole package folder, build trees inside
# it included, and refuses a name it finds twice.
set(_objmap_source_config "$(find objmap)/server/core/config/objmap.example.yaml")
set(_objmap_installed_config "$(find objmap)/objmap.example.yaml")
file(GLOB _objmap_launch_files ${PROJECT_SOURCE_DIR}/launch/*.launch)
foreach(launch_file ${_objmap_launch_files})
  get_filename_component(name ${launch_file} NAME)
  file(READ ${launch_file} text)
  string(REPLACE "${_objmap_source_config}" "${_objmap_installed_config}" text "${text}")
  file(WRITE ${PROJECT_BINARY_DIR}/installed_launch/${name}.installed "${text}")
  # A build tree configured by an older objmap holds them under their own name.
  file(REMOVE ${PROJECT_BINARY_DIR}/installed_launch/${name})
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${launch_file})
  install(FILES ${PROJECT_BINARY_DIR}/installed_launch/${name}.installed
    DESTINATION ${OBJMAP_INSTALL_SHARE_DIR}/launch RENAME ${name})
endforeach()
install(FILES ${PROJECT_SOURCE_DIR}/launch/objmap.rviz DESTINATION ${OBJMAP_INSTALL_SHARE_DIR}/launch)

# catkin's setup files for the install (generated in catkin_generated/installspace, not installed
# by catkin itself: cmake/objmap_ros.cmake). setup.bash and setup.zsh find their own folder; the
# sh files name the prefix, which is only known at install time.
if(OBJMAP_ROS_ENABLED)
  set(_objmap_catkin_installspace ${PROJECT_BINARY_DIR}/catkin_generated/installspace)
  install(FILES ${_objmap_catkin_installspace}/setup.bash ${_objmap_catkin_installspace}/setup.zsh
    ${_objmap_catkin_installspace}/local_setup.bash ${_objmap_catkin_installspace}/local_setup.zsh
    DESTINATION .)
  # catkin generates _setup_util.py for the install only when it installs it itself; the devel
  # space's is the same file (nothing in it names a prefix).
  install(PROGRAMS ${CATKIN_DEVEL_PREFIX}/_setup_util.py ${_objmap_catkin_installspace}/env.sh
    DESTINATION .)
  install(CODE "
    set(_prefix \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}\")
    foreach(_name setup.sh local_setup.sh)
      file(READ \"${_objmap_catkin_installspace}/\${_name}\" _text)
      string(REPLACE \"_CATKIN_SETUP_DIR:=${CMAKE_INSTALL_PREFIX}}\"
        \"_CATKIN_SETUP_DIR:=\${CMAKE_INSTALL_PREFIX}}\" _text \"\${_text}\")
      file(WRITE \"\${_prefix}/\${_name}\" \"\${_text}\")
      message(STATUS \"Installing: \${_prefix}/\${_name}\")
    endforeach()
    # The marker that makes the prefix a catkin workspace (its share/ joins ROS_PACKAGE_PATH).
    if(NOT EXISTS \"\${_prefix}/.catkin\")
      file(WRITE \"\${_prefix}/.catkin\" \"\")
    endif()")
endif()

# roslaunch finds the package by its manifest (catkin_package installs it too in workspaces).
if(NOT OBJMAP_ROS_ENABLED)
  install(FILES ${PROJECT_SOURCE_DIR}/package.xml DESTINATION ${OBJMAP_INSTALL_SHARE_DIR})
endif()
