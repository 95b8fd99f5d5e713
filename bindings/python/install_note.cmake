# Run by `cmake --install` after the Python package is in place
# (bindings/python/CMakeLists.txt sets DPSM_PYTHONDIR and DPSM_PYTHON first):
# one line saying where the package went and, when the interpreter the build
# found does not look there, what to add to PYTHONPATH.
cmake_policy(VERSION 3.16)  # install scripts otherwise run with every policy OLD
if(IS_ABSOLUTE "${DPSM_PYTHONDIR}")
  set(_dir "${DPSM_PYTHONDIR}")
else()
  set(_dir "${CMAKE_INSTALL_PREFIX}/${DPSM_PYTHONDIR}")
endif()
file(TO_CMAKE_PATH "${_dir}" _dir)
string(REGEX REPLACE "/+$" "" _dir "${_dir}")

if(NOT DPSM_PYTHON OR NOT EXISTS "${DPSM_PYTHON}")
  message(STATUS "dpsm: the Python package dpsm went to ${_dir}/dpsm; no Python interpreter was found to ask "
                 "whether it looks there: if yours does not, export PYTHONPATH=${_dir}")
  return()
endif()

# The interpreter's own search path, without what PYTHONPATH adds now.
execute_process(
  COMMAND "${CMAKE_COMMAND}" -E env --unset=PYTHONPATH "${DPSM_PYTHON}" -c
          "import os, sys; print(';'.join(os.path.realpath(p) for p in sys.path if p))"
  OUTPUT_VARIABLE _paths OUTPUT_STRIP_TRAILING_WHITESPACE RESULT_VARIABLE _rc ERROR_QUIET)
get_filename_component(_real "${_dir}" REALPATH)
list(FIND _paths "${_real}" _at)
if(_rc EQUAL 0 AND _at GREATER -1)
  message(STATUS "dpsm: the Python package dpsm went to ${_dir}/dpsm, where ${DPSM_PYTHON} finds it")
else()
  message(STATUS "dpsm: the Python package dpsm went to ${_dir}/dpsm, where ${DPSM_PYTHON} does not look: "
                 "export PYTHONPATH=${_dir}")
endif()
