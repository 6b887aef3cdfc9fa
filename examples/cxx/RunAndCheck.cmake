# cmake -DEXPECT_EXIT=zero|nonzero -DEXPECT_OUTPUT=REGEX [-DEXPECT_FILE=PATH] -P RunAndCheck.cmake
#       -- COMMAND [ARG...]
#
# Runs COMMAND and checks both its exit status and its output (stdout and stderr together), and
# optionally that it wrote EXPECT_FILE: a test of a program's error handling needs both, while
# ctest's PASS_REGULAR_EXPRESSION alone ignores the exit status.
set(command)
set(after_separator OFF)
math(EXPR last "${CMAKE_ARGC} - 1")
foreach(i RANGE ${last})
  if(after_separator)
    list(APPEND command "${CMAKE_ARGV${i}}")
  elseif(CMAKE_ARGV${i} STREQUAL "--")
    set(after_separator ON)
  endif()
endforeach()
if(NOT command OR NOT EXPECT_EXIT MATCHES "^(zero|nonzero)$" OR NOT DEFINED EXPECT_OUTPUT)
  message(FATAL_ERROR "usage: cmake -DEXPECT_EXIT=zero|nonzero -DEXPECT_OUTPUT=REGEX "
    "[-DEXPECT_FILE=PATH] -P RunAndCheck.cmake -- COMMAND [ARG...]")
endif()

if(DEFINED EXPECT_FILE)
  file(REMOVE "${EXPECT_FILE}")
endif()
execute_process(COMMAND ${command} RESULT_VARIABLE status OUTPUT_VARIABLE output
  ERROR_VARIABLE output)
message("${output}")

if(EXPECT_EXIT STREQUAL "zero" AND NOT status STREQUAL "0")
  message(FATAL_ERROR "expected exit status 0, got '${status}'")
elseif(EXPECT_EXIT STREQUAL "nonzero" AND status STREQUAL "0")
  message(FATAL_ERROR "expected a non-zero exit status, got 0")
endif()
if(NOT output MATCHES "${EXPECT_OUTPUT}")
  message(FATAL_ERROR "the output does not match '${EXPECT_OUTPUT}'")
endif()
if(DEFINED EXPECT_FILE AND NOT EXISTS "${EXPECT_FILE}")
  message(FATAL_ERROR "'${EXPECT_FILE}' was not written")
endif()
