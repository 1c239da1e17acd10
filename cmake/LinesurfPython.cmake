# The Python module `linesurf` (python/): pybind11 from Debian (pybind11-dev), numpy, and the
# interpreter that has numpy. `python3` on PATH may be another interpreter without numpy (pyenv),
# so unless Python3_EXECUTABLE is given we take the first of /usr/bin/python3 and PATH's python3
# that imports numpy. The module lands in build/python/linesurf (PYTHONPATH=build/python) and is
# installed to <prefix>/lib/pythonX.Y/site-packages (cmake --install build --prefix ~/.local).
if(NOT LINESURF_PYTHON)
  return()
endif()

if(NOT Python3_EXECUTABLE)
  find_program(LINESURF_PATH_PYTHON3 python3)
  foreach(candidate /usr/bin/python3 ${LINESURF_PATH_PYTHON3})
    if(EXISTS ${candidate})
      execute_process(COMMAND ${candidate} -c "import numpy" RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
      if(rc EQUAL 0)
        set(Python3_EXECUTABLE ${candidate} CACHE FILEPATH "Python interpreter with numpy for the linesurf module")
        break()
      endif()
    endif()
  endforeach()
endif()
find_package(Python3 COMPONENTS Interpreter Development.Module NumPy)
if(Python3_FOUND AND Python3_NumPy_FOUND)
  find_package(pybind11 CONFIG QUIET)
endif()
if(NOT (Python3_FOUND AND Python3_NumPy_FOUND AND pybind11_FOUND))
  message(STATUS "linesurf: Python module skipped (needs python3-dev, python3-numpy, pybind11-dev)")
  return()
endif()
message(STATUS "linesurf: Python module for ${Python3_EXECUTABLE} (${Python3_VERSION}), pybind11 ${pybind11_VERSION}")

set(LINESURF_PYTHON_DIR ${PROJECT_BINARY_DIR}/python/linesurf)
file(GLOB LINESURF_PYTHON_SOURCES CONFIGURE_DEPENDS ${PROJECT_SOURCE_DIR}/python/src/*.cpp)
pybind11_add_module(linesurf_python MODULE ${LINESURF_PYTHON_SOURCES})
target_link_libraries(linesurf_python PRIVATE linesurf_lib Python3::NumPy)
# pybind11 links the module with -flto; let GCC split the link-time work over the cores (make's
# jobserver or all of them) instead of warning that it runs the 7 LTRANS jobs serially
if(CMAKE_CXX_COMPILER_ID STREQUAL "GNU")
  target_link_options(linesurf_python PRIVATE -flto=auto)
endif()
set_target_properties(linesurf_python PROPERTIES OUTPUT_NAME _linesurf LIBRARY_OUTPUT_DIRECTORY ${LINESURF_PYTHON_DIR})
foreach(f __init__.py __init__.pyi py.typed)
  configure_file(${PROJECT_SOURCE_DIR}/python/linesurf/${f} ${LINESURF_PYTHON_DIR}/${f} COPYONLY)
endforeach()

set(LINESURF_PYTHON_INSTALL_DIR lib/python${Python3_VERSION_MAJOR}.${Python3_VERSION_MINOR}/site-packages
    CACHE STRING "Where `cmake --install` puts the linesurf Python package, relative to the prefix")
install(TARGETS linesurf_python LIBRARY DESTINATION ${LINESURF_PYTHON_INSTALL_DIR}/linesurf)
install(FILES ${LINESURF_PYTHON_DIR}/__init__.py ${LINESURF_PYTHON_DIR}/__init__.pyi ${LINESURF_PYTHON_DIR}/py.typed
        DESTINATION ${LINESURF_PYTHON_INSTALL_DIR}/linesurf)

execute_process(COMMAND ${Python3_EXECUTABLE} -c "import pytest" RESULT_VARIABLE rc OUTPUT_QUIET ERROR_QUIET)
if(rc EQUAL 0)
  add_test(NAME PythonModule
    COMMAND ${Python3_EXECUTABLE} -m pytest -q -p no:cacheprovider ${PROJECT_SOURCE_DIR}/tests/python)
  set_tests_properties(PythonModule PROPERTIES TIMEOUT 900
    ENVIRONMENT "PYTHONPATH=${PROJECT_BINARY_DIR}/python;LINESURF_CLI=$<TARGET_FILE:linesurf>;LINESURF_SOURCE_DIR=${PROJECT_SOURCE_DIR}")
else()
  message(STATUS "linesurf: pytest not found for ${Python3_EXECUTABLE}: Python tests not registered")
endif()

# bench/python_overhead.py compares the module's render call with this C++ one.
add_executable(linesurf_python_overhead EXCLUDE_FROM_ALL ${PROJECT_SOURCE_DIR}/bench/python_overhead.cpp)
target_link_libraries(linesurf_python_overhead PRIVATE linesurf_lib)

# The PackageConsumer test also imports the module from the installed prefix.
set_property(TEST PackageConsumer APPEND PROPERTY ENVIRONMENT
  "LINESURF_PYTHON=${Python3_EXECUTABLE};LINESURF_PYTHON_SITE=${LINESURF_PYTHON_INSTALL_DIR}")
