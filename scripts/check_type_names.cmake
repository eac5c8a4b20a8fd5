# The type-name check: no two types declared at namespace scope in src/, include/ and apps/ share a name,
# except those in an anonymous namespace of a .cpp file (which are private to it). Two types of one
# qualified name linked into one program break the one-definition rule, and no ordinary build says so
# (GCC's -Wodr reports it only when linking with -flto): the LAS reader's abstract source of records and
# the finalise step's pointer to a journal record were both city3d::detail::RecordSource. Names are
# compared without their namespace, so the same name in two namespaces is refused too: one name, one type.
#
# It reads the code's layout, not its grammar: a type at namespace scope starts at column 0 (the style of
# .clang-format, which does not indent namespaces), an anonymous namespace opens with "namespace {" at
# column 0 and closes with "}  // namespace"; a line ending in ";" (before a comment) declares without
# defining, and "struct Name::Part" defines a member of Name. The build runs it before compiling
# (target `type_names`).
#
# Usage: cmake -DROOT=<source folder> -P check_type_names.cmake
if(NOT ROOT)
  message(FATAL_ERROR "check_type_names: give -DROOT=<source folder>")
endif()
get_filename_component(ROOT "${ROOT}" ABSOLUTE)
file(GLOB_RECURSE files RELATIVE "${ROOT}" "${ROOT}/src/*.hpp" "${ROOT}/src/*.cpp" "${ROOT}/include/*.hpp"
     "${ROOT}/apps/*.hpp" "${ROOT}/apps/*.cpp")
list(SORT files)
set(names "")
set(problems "")
foreach(file IN LISTS files)
  file(STRINGS "${ROOT}/${file}" lines REGEX "^(namespace|}|struct |class |enum |union )")
  set(anonymous FALSE)
  foreach(line IN LISTS lines)
    if(line MATCHES "^namespace *{")
      set(anonymous TRUE)
    elseif(anonymous AND line MATCHES "^} *// *namespace *$")
      set(anonymous FALSE)
    elseif(NOT anonymous AND line MATCHES "^(struct|class|enum class|enum struct|enum|union) ([A-Za-z_][A-Za-z0-9_]*)(.*)$")
      set(name "${CMAKE_MATCH_2}")
      set(rest "${CMAKE_MATCH_3}")
      string(REGEX REPLACE "//.*$" "" code "${rest}")
      string(STRIP "${code}" code)
      if(rest MATCHES "^::" OR code MATCHES ";$")
        continue()
      endif()
      if(DEFINED defined_in_${name})
        string(APPEND problems "\n  ${name}: ${defined_in_${name}} and ${file}")
      else()
        set(defined_in_${name} "${file}")
        list(APPEND names ${name})
      endif()
    endif()
  endforeach()
endforeach()
if(problems)
  message(FATAL_ERROR "check_type_names: types of the same name (rename one, or move a private one into an "
                      "anonymous namespace):${problems}")
endif()
list(LENGTH names count)
message(STATUS "check_type_names: ${count} type names, each defined once")
