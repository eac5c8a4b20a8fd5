# Writes a C++ source that holds a text file, cut in two at a marker, as two NUL-terminated char arrays:
# the program writes the first, then what it generates, then the second (report.html's page around the
# run's data). The bytes are written as character literals ('\x3c'), so the program writes exactly the
# file's bytes: no escaping to get wrong and no limit on the length of a string literal.
#
# cmake -DINPUT=<template> -DOUTPUT=<source.cpp> -DMARKER=<text> -DHEADER=<include> -DNAMESPACE=<ns>
#       -DHEAD=<name> -DTAIL=<name> -P embed_text.cmake
# HEADER declares both arrays (extern const char NAME[];), so that they have external linkage.
cmake_minimum_required(VERSION 3.22)  # string(HEX)
foreach(arg INPUT OUTPUT MARKER HEADER NAMESPACE HEAD TAIL)
  if(NOT DEFINED ${arg} OR "${${arg}}" STREQUAL "")
    message(FATAL_ERROR "embed_text.cmake: -D${arg}=... is required")
  endif()
endforeach()

file(READ "${INPUT}" text)
string(FIND "${text}" "${MARKER}" at)
string(FIND "${text}" "${MARKER}" last REVERSE)
if(at EQUAL -1 OR NOT at EQUAL last)
  message(FATAL_ERROR "embed_text.cmake: ${INPUT} must hold ${MARKER} exactly once")
endif()
string(LENGTH "${MARKER}" marker_length)
math(EXPR after "${at} + ${marker_length}")
string(SUBSTRING "${text}" 0 ${at} head)
string(SUBSTRING "${text}" ${after} -1 tail)

# The bytes of `piece` as an initializer list, 16 a line, ending with the terminating NUL.
function(char_array piece out)
  string(HEX "${piece}" hex)
  string(REGEX REPLACE "([0-9a-f][0-9a-f])" "'\\\\x\\1'," chars "${hex}")
  string(REPEAT "'\\\\x..'," 16 sixteen)  # CMake's regular expressions have no {16}
  string(REGEX REPLACE "(${sixteen})" "\\1\n" chars "${chars}")
  set(${out} "${chars}0" PARENT_SCOPE)
endfunction()
char_array("${head}" head_chars)
char_array("${tail}" tail_chars)

get_filename_component(input_name "${INPUT}" NAME)
file(WRITE "${OUTPUT}" "// Generated from ${input_name} by cmake/embed_text.cmake: edit the template, not this file.
#include \"${HEADER}\"

namespace ${NAMESPACE} {

const char ${HEAD}[] = {
${head_chars}};

const char ${TAIL}[] = {
${tail_chars}};

}  // namespace ${NAMESPACE}
")
