# The DBC agreement test: a C helper exposing the codec, driven by pytest
# with cantools (tests/can/test_dbc_agreement.py).
add_executable(can_codec_tool ${CMAKE_CURRENT_SOURCE_DIR}/can/can_codec_tool.c)
target_link_libraries(can_codec_tool PRIVATE fd_app fd_hal_sil m)
fd_host_target(can_codec_tool)
if(FD_PYTHON)
  add_test(NAME can/dbc_agreement
           COMMAND ${FD_PYTHON} -m pytest -q -p no:cacheprovider
                   ${CMAKE_CURRENT_SOURCE_DIR}/can/test_dbc_agreement.py
           WORKING_DIRECTORY ${PROJECT_SOURCE_DIR})
  set_tests_properties(can/dbc_agreement PROPERTIES LABELS can TIMEOUT 300
    ENVIRONMENT "FD_CAN_CODEC_TOOL=$<TARGET_FILE:can_codec_tool>")
endif()
