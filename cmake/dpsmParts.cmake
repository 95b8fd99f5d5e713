# The optional parts of the build (tests, docs, the Fortran binding): each is
# a cache variable that is AUTO, ON or OFF.
#   AUTO (the default)  built when its tools are found; otherwise skipped with
#                       one STATUS line naming what is missing and the Debian
#                       package that brings it, so the plain build works with
#                       only a compiler and CMake;
#   ON                  required: without its tools, configuring fails with
#                       that same message;
#   OFF                 not built, not looked for.

# Declares the part's cache variable (unless the cache has it already).
function(dpsm_part option description)
  set(${option} AUTO CACHE STRING "${description}: AUTO (when its tools are found), ON (required) or OFF")
  set_property(CACHE ${option} PROPERTY STRINGS AUTO ON OFF)
endfunction()

# Whether the part is wanted at all: false for OFF (and its synonyms), so its
# tools are not even looked for. Fails on a value that is neither.
function(dpsm_part_wanted option result)
  string(TOUPPER "${${option}}" value)
  if(value STREQUAL "AUTO" OR value MATCHES "^(ON|YES|TRUE|Y|1)$")
    set(${result} TRUE PARENT_SCOPE)
  elseif(value MATCHES "^(OFF|NO|FALSE|N|0|)$")
    set(${result} FALSE PARENT_SCOPE)
  else()
    message(FATAL_ERROR "dpsm: ${option} = ${${option}}: give AUTO, ON or OFF")
  endif()
endfunction()

# Sets <option>_ENABLED in the caller: true when the part is wanted and
# `found` is true. An AUTO part without its tools prints one STATUS line
# "dpsm: <what> not built: <missing> (<how to get it>)"; an ON one fails with
# the same words.
function(dpsm_part_decide option found what missing how)
  dpsm_part_wanted(${option} wanted)
  string(TOUPPER "${${option}}" value)
  if(NOT wanted)
    set(${option}_ENABLED FALSE PARENT_SCOPE)
  elseif(found)
    set(${option}_ENABLED TRUE PARENT_SCOPE)
  elseif(value STREQUAL "AUTO")
    message(STATUS "dpsm: ${what} not built: ${missing} (${how}; then configure again)")
    set(${option}_ENABLED FALSE PARENT_SCOPE)
  else()
    message(FATAL_ERROR "dpsm: ${option}=${${option}} asks for ${what}, but ${missing}: ${how}, "
                        "or configure with -D${option}=AUTO to build without them")
  endif()
endfunction()

# The tests need CMocka, found through pkg-config (PkgConfig::CMOCKA).
macro(dpsm_decide_tests)
  dpsm_part_wanted(DPSM_BUILD_TESTS _dpsm_tests_wanted)
  if(_dpsm_tests_wanted)
    find_package(PkgConfig QUIET)
    if(PKG_CONFIG_FOUND)
      pkg_check_modules(CMOCKA QUIET IMPORTED_TARGET cmocka)
    endif()
  endif()
  if(NOT PKG_CONFIG_FOUND)
    set(_dpsm_cmocka_missing "pkg-config was not found, through which the tests find CMocka")
  else()
    set(_dpsm_cmocka_missing "CMocka was not found (pkg-config knows no cmocka)")
  endif()
  dpsm_part_decide(DPSM_BUILD_TESTS "${CMOCKA_FOUND}" "the tests" "${_dpsm_cmocka_missing}"
                   "install libcmocka-dev and pkg-config: apt-get install libcmocka-dev pkg-config")
endmacro()

# The docs need doxygen.
macro(dpsm_decide_docs)
  dpsm_part_wanted(DPSM_BUILD_DOCS _dpsm_docs_wanted)
  if(_dpsm_docs_wanted)
    find_package(Doxygen QUIET)
  endif()
  dpsm_part_decide(DPSM_BUILD_DOCS "${DOXYGEN_FOUND}" "the API reference and the docs test"
                   "doxygen was not found" "install doxygen: apt-get install doxygen")
endmacro()
