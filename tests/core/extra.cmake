# tests/core/extra.cmake - Eigen (double) reference checks of the core's
# flux map. Included from tests/CMakeLists.txt inside fd_add_cmocka_tests().
find_path(FD_EIGEN3_INCLUDE Eigen/Core PATHS /usr/include/eigen3 NO_DEFAULT_PATH)
if(NOT FD_EIGEN3_INCLUDE)
  message(FATAL_ERROR "Eigen3 not found (Debian: libeigen3-dev)")
endif()
foreach(ref ref_flux_map)
  set(exe core_${ref})
  add_executable(${exe} ${CMAKE_CURRENT_SOURCE_DIR}/core/${ref}.cpp)
  set_target_properties(${exe} PROPERTIES CXX_STANDARD 17 CXX_STANDARD_REQUIRED ON)
  target_include_directories(${exe} PRIVATE ${CMOCKA_INCLUDE} ${FD_EIGEN3_INCLUDE}
                             ${CMAKE_CURRENT_SOURCE_DIR}/core)
  target_link_libraries(${exe} PRIVATE fd_core ${CMOCKA_LIB} m)
  target_compile_options(${exe} PRIVATE -Wall -Wextra -Werror)
  add_test(NAME core/${ref} COMMAND ${exe})
  set_tests_properties(core/${ref} PROPERTIES LABELS core TIMEOUT 300)
endforeach()
