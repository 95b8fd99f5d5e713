# cmake -DCMAKE_PREFIX_PATH=<prefix> -P version_check.cmake
# The installed package (SameMajorVersion) must refuse a request for another
# major version or a newer minor one. A refused package is not loaded, so this
# runs in script mode; the consumer project checks that `0.1` is accepted.
cmake_minimum_required(VERSION 3.16)
foreach(request 1.0 0.99)
  find_package(dpsm ${request} CONFIG QUIET)
  if(dpsm_FOUND)
    message(FATAL_ERROR "find_package(dpsm ${request}) found version ${dpsm_VERSION}; it should refuse it")
  endif()
  if(NOT dpsm_CONSIDERED_VERSIONS)
    message(FATAL_ERROR "find_package(dpsm ${request}) saw no dpsm package at all under ${CMAKE_PREFIX_PATH}")
  endif()
  message(STATUS "find_package(dpsm ${request}) refused versions ${dpsm_CONSIDERED_VERSIONS}, as it should")
endforeach()
