# host_sim/robots: every robot folder (DYNCAL_ROBOT_DIRS, top-level CMakeLists.txt) compiled into the
# host tools. Per robot: its generated model (committed lib/generated/<name>/ for the shipped robots,
# else generated here into the build tree by codegen/generate.py whenever robot.json, a URDF of the
# folder or the generator changes) and translation units made from the templates in this
# folder, which register the robot's operations by name at start-up: the model (robot_model.cpp.in,
# compiled_robot.hpp), the identification models of the built term sets (robot_identify.cpp.in:
# layout, generated regressor, least squares; the pipeline is compiled once, identify_pipeline.cpp,
# and so are the KF and RLS, at the model's run-time size: recursive_fit.cpp) and the simulated
# drive's plant (robot_drive.cpp.in, drive_plant.hpp). The three compile as one unity unit per robot
# (UNITY_GROUP <robot>), so that their Eigen instantiations are compiled once. Adding a robot
# compiles only its own unit. The test robots (tests/robots/) go into the test programs and
# dyncal_test_cli, not into the dyncal program. Part `robots` of the dependency rule: it depends on
# model (the registry) and drive.
set(DYNCAL_ROBOTS_GENERATED ${CMAKE_BINARY_DIR}/robots_generated)
file(GLOB codegen_sources ${PROJECT_SOURCE_DIR}/codegen/*.py ${PROJECT_SOURCE_DIR}/codegen/dyncal_codegen/*.py)
set(robot_sources "")       # robots/*: the robots the dyncal program ships with (and the user's)
set(test_robot_sources "")  # tests/robots/*: test fixtures, compiled into the test programs only
foreach(dir ${DYNCAL_ROBOT_DIRS})
  get_filename_component(DYNCAL_ROBOT ${dir} NAME)
  file(RELATIVE_PATH DYNCAL_ROBOT_DIR ${PROJECT_SOURCE_DIR} ${dir})
  set(sources "")
  if(NOT DYNCAL_ROBOT IN_LIST DYNCAL_ROBOTS)
    set(out ${DYNCAL_ROBOTS_GENERATED}/dyncal/generated/${DYNCAL_ROBOT})
    file(GLOB inputs CONFIGURE_DEPENDS ${dir}/*.json ${dir}/*.urdf)
    set(headers ${out}/robot.hpp ${out}/dynamics.hpp ${out}/parameters.hpp ${out}/regressor.hpp)
    add_custom_command(OUTPUT ${headers}
      COMMAND /usr/bin/python3 ${PROJECT_SOURCE_DIR}/codegen/generate.py ${dir} ${out}
      DEPENDS ${inputs} ${codegen_sources}
      COMMENT "Generating the ${DYNCAL_ROBOT} model from ${DYNCAL_ROBOT_DIR}" VERBATIM)
    list(APPEND sources ${headers})
  endif()
  set(unit ${CMAKE_CURRENT_BINARY_DIR}/robots/${DYNCAL_ROBOT})
  configure_file(${CMAKE_CURRENT_LIST_DIR}/robot_model.cpp.in ${unit}_model.cpp @ONLY)
  configure_file(${CMAKE_CURRENT_LIST_DIR}/robot_drive.cpp.in ${unit}_drive.cpp @ONLY)
  configure_file(${CMAKE_CURRENT_LIST_DIR}/robot_identify.cpp.in ${unit}_identify.cpp @ONLY)
  list(APPEND sources ${unit}_model.cpp ${unit}_identify.cpp ${unit}_drive.cpp)
  set_source_files_properties(${unit}_model.cpp ${unit}_identify.cpp ${unit}_drive.cpp PROPERTIES
    UNITY_GROUP ${DYNCAL_ROBOT})
  if(DYNCAL_ROBOT_DIR MATCHES "^tests/")
    list(APPEND test_robot_sources ${sources})
  else()
    list(APPEND robot_sources ${sources})
  endif()
endforeach()
# dyncal_host_robots: the shipped and the user's robots (the dyncal program); dyncal_host_test_robots:
# the test robots (the test programs and dyncal_test_cli). An empty set gets an empty unit.
foreach(set robot_sources test_robot_sources)
  if(NOT ${set})
    file(WRITE ${CMAKE_CURRENT_BINARY_DIR}/robots/no_${set}.cpp "// no robot folder in this set\n")
    set(${set} ${CMAKE_CURRENT_BINARY_DIR}/robots/no_${set}.cpp)
  endif()
endforeach()
foreach(target dyncal_host_robots dyncal_host_test_robots)
  if(target STREQUAL dyncal_host_robots)
    add_library(${target} OBJECT ${robot_sources})
  else()
    add_library(${target} OBJECT ${test_robot_sources})
  endif()
  target_include_directories(${target} PRIVATE ${DYNCAL_ROBOTS_GENERATED} ${CMAKE_CURRENT_LIST_DIR}/include)
  target_link_libraries(${target} PUBLIC dyncal_host_model dyncal_host_drive)
  target_compile_options(${target} PRIVATE ${DYNCAL_WARNINGS})
  set_target_properties(${target} PROPERTIES UNITY_BUILD ON UNITY_BUILD_MODE GROUP)
endforeach()
# One precompiled header for every robot's unit: the headers all of them parse (Eigen, the drive
# plant's and the registry's templates).
target_precompile_headers(dyncal_host_robots PRIVATE <Eigen/Dense> <dyncal_host/drive/drive_plant_of.hpp>
  <dyncal_host/robots/register_robot.hpp> <utility>)
target_precompile_headers(dyncal_host_test_robots REUSE_FROM dyncal_host_robots)
set_property(GLOBAL PROPERTY DYNCAL_HOST_CLOSURE_robots "model;logs;drive;common")
set_property(GLOBAL APPEND PROPERTY DYNCAL_HOST_PARTS robots)
