# Profile-guided optimisation of the SIL runner (host Release, GCC).
#
# fd_sil_pgo(TARGETS...) in a host Release build (not sanitized, GCC,
# FD_SIL_PGO on, the default):
#   1. builds an instrumented copy of the runner (-fprofile-generate) in
#      <build>/pgo/build: the same sources, this tree, a nested CMake build
#      (ExternalProject) with FD_SIL_PGO_GENERATE set;
#   2. runs it on the training scenarios (FD_SIL_PGO_TRAIN: one of each
#      law family, both inverter models, a flux map; cmake/pgo_train.cmake),
#      profile in <build>/pgo/profile;
#   3. compiles TARGETS with -fprofile-use on that profile: branch layout,
#      inlining and unrolling follow the measured counts.
# No floating-point semantics change (no -ffast-math, no -march, no
# contraction without FMA): the logs and summaries are byte-identical to
# the build without it (docs/benchmarks.md); the binary runs on any x86-64.
# The profile's digest (pgo/profile.stamp, rewritten only when it differs)
# is an OBJECT_DEPENDS of every source of TARGETS: a source change that
# changes the counts recompiles the runner on the new profile, and the
# figures of an incremental build equal a clean build's.
# Off: -DFD_SIL_PGO=OFF (one build, as before).
option(FD_SIL_PGO "host Release: profile-guided optimisation of the SIL runner (GCC)" ON)
set(FD_SIL_PGO_GENERATE "" CACHE PATH "internal: the instrumented build writes its profile here")
set(FD_SIL_PGO_TRAIN
    default foc_speed_load rubino_torque_step_pi varatharajan_speed_step fabbri_speed
    syr_1k1_speed_load
    CACHE STRING "scenarios (sil/scenarios/NAME.json) the profile is measured on")

function(fd_sil_pgo)
  if(NOT CMAKE_BUILD_TYPE STREQUAL "Release" OR FD_SANITIZE OR NOT CMAKE_C_COMPILER_ID STREQUAL "GNU")
    return()
  endif()
  if(FD_SIL_PGO_GENERATE)
    # the instrumented build (step 1): counters, one thread (-fprofile-update=single:
    # the preemption thread never runs in training); object names relative to
    # this build directory, as the optimised build's
    foreach(tgt IN LISTS ARGN)
      target_compile_options(${tgt} PRIVATE -fprofile-generate=${FD_SIL_PGO_GENERATE}
                             -fprofile-update=single -fprofile-prefix-path=${CMAKE_BINARY_DIR})
    endforeach()
    target_link_options(fluxdrive-sil PRIVATE -fprofile-generate)
    return()
  endif()
  if(NOT FD_SIL_PGO)
    return()
  endif()
  include(ExternalProject)
  set(pgo ${CMAKE_BINARY_DIR}/pgo)
  set(runner ${pgo}/build/sil/fluxdrive-sil)
  ExternalProject_Add(
    fd_sil_pgo_runner
    SOURCE_DIR ${PROJECT_SOURCE_DIR}
    BINARY_DIR ${pgo}/build
    PREFIX ${pgo}/ep
    CMAKE_ARGS -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF -DFD_SIL_PGO=OFF
               -DFD_SIL_PGO_GENERATE=${pgo}/profile -DCMAKE_C_COMPILER=${CMAKE_C_COMPILER}
    BUILD_COMMAND ${CMAKE_COMMAND} --build <BINARY_DIR> --target fluxdrive-sil
    BUILD_ALWAYS TRUE
    BUILD_BYPRODUCTS ${runner}
    INSTALL_COMMAND ""
    TEST_COMMAND "")
  # step 2: reruns when the instrumented runner changed (Ninja's restat:
  # the stamp keeps its time when the profile is the same)
  add_custom_command(
    OUTPUT ${pgo}/trained
    BYPRODUCTS ${pgo}/profile.stamp
    COMMAND ${CMAKE_COMMAND} -DRUNNER=${runner} -DPROFILE=${pgo}/profile
            -DSTAMP=${pgo}/profile.stamp -DSCENARIOS=${PROJECT_SOURCE_DIR}/sil/scenarios
            "-DTRAIN=${FD_SIL_PGO_TRAIN}" -P ${PROJECT_SOURCE_DIR}/cmake/pgo_train.cmake
    COMMAND ${CMAKE_COMMAND} -E touch ${pgo}/trained
    DEPENDS ${runner} ${PROJECT_SOURCE_DIR}/cmake/pgo_train.cmake
    COMMENT "SIL profile-guided optimisation: training run"
    VERBATIM)
  add_custom_target(fd_sil_pgo_profile DEPENDS ${pgo}/trained)
  add_dependencies(fd_sil_pgo_profile fd_sil_pgo_runner)
  foreach(tgt IN LISTS ARGN)
    add_dependencies(${tgt} fd_sil_pgo_profile)
    target_compile_options(${tgt} PRIVATE -fprofile-use=${pgo}/profile
                           -fprofile-prefix-path=${CMAKE_BINARY_DIR} -Wno-missing-profile)
    get_target_property(srcs ${tgt} SOURCES)
    set_source_files_properties(${srcs} TARGET_DIRECTORY ${tgt} PROPERTIES OBJECT_DEPENDS
                                                                          ${pgo}/profile.stamp)
  endforeach()
  target_link_options(fluxdrive-sil PRIVATE -fprofile-use=${pgo}/profile)
endfunction()
