# Injected by tests/ros/setup-ros-env.sh with
#   -DCMAKE_PROJECT_INCLUDE=<this file>
# so that the interface package's CMakeLists.txt stays stock.
#
# Why: the PyPI ros-* wheels export `<pkg>::<pkg>__rosidl_generator_py`
# imported targets whose INTERFACE_INCLUDE_DIRECTORIES name the wheel-build
# container's Python and NumPy headers (/opt/python/cp3XX-cp3XX/...). Those
# paths do not exist here, and CMake stops at generate time with
# "Imported target ... includes non-existent path". At the end of configure
# (after every find_package of the project ran) this rewrites those targets'
# include dirs: entries that do not exist are dropped and this machine's
# Python and NumPy include dirs are added.
#
# CMAKE_PROJECT_INCLUDE runs after every project() call; the guard keeps it to
# the first one. cmake_language(DEFER) needs CMake >= 3.19 and the directory
# property IMPORTED_TARGETS CMake >= 3.21.

include_guard(GLOBAL)
if(CMAKE_VERSION VERSION_LESS 3.21)
  message(FATAL_ERROR "dynevent: ${CMAKE_CURRENT_LIST_FILE} needs CMake >= 3.21")
endif()

function(_dynevent_fix_rosidl_py_include_dirs)
  if(NOT Python3_INCLUDE_DIRS OR NOT Python3_NumPy_INCLUDE_DIRS)
    find_package(Python3 REQUIRED COMPONENTS Interpreter Development.Module NumPy)
  endif()
  set(_here_dirs ${Python3_INCLUDE_DIRS} ${Python3_NumPy_INCLUDE_DIRS})

  get_property(_targets DIRECTORY "${CMAKE_SOURCE_DIR}" PROPERTY IMPORTED_TARGETS)
  set(_fixed "")
  foreach(_target IN LISTS _targets)
    if(NOT _target MATCHES "__rosidl_generator_py$")
      continue()
    endif()
    get_target_property(_dirs ${_target} INTERFACE_INCLUDE_DIRECTORIES)
    if(NOT _dirs)
      continue()
    endif()
    set(_kept "")
    set(_dropped FALSE)
    foreach(_dir IN LISTS _dirs)
      if(_dir MATCHES "^\\$<" OR EXISTS "${_dir}")
        list(APPEND _kept "${_dir}")
      else()
        set(_dropped TRUE)
      endif()
    endforeach()
    if(_dropped)
      list(APPEND _kept ${_here_dirs})
      list(REMOVE_DUPLICATES _kept)
      set_target_properties(${_target} PROPERTIES INTERFACE_INCLUDE_DIRECTORIES "${_kept}")
      list(APPEND _fixed ${_target})
    endif()
  endforeach()
  if(_fixed)
    list(JOIN _fixed ", " _names)
    message(STATUS "dynevent: include dirs of ${_names} set to ${_here_dirs}")
  endif()
endfunction()

cmake_language(DEFER DIRECTORY "${CMAKE_SOURCE_DIR}" CALL _dynevent_fix_rosidl_py_include_dirs)
