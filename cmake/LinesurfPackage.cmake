# `cmake --install build --prefix P` installs the static library, the public headers, the CLI and
# P/lib/cmake/linesurf/{linesurfConfig,linesurfConfigVersion,linesurfTargets}.cmake, so that a
# consumer writes find_package(linesurf REQUIRED) and links linesurf::linesurf.
include(CMakePackageConfigHelpers)
set(LINESURF_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/linesurf)

install(TARGETS linesurf_lib EXPORT linesurfTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(TARGETS linesurf RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/linesurf DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(EXPORT linesurfTargets NAMESPACE linesurf:: DESTINATION ${LINESURF_CMAKE_DIR})

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/linesurfConfig.cmake.in
  ${PROJECT_BINARY_DIR}/linesurfConfig.cmake INSTALL_DESTINATION ${LINESURF_CMAKE_DIR})
write_basic_package_version_file(${PROJECT_BINARY_DIR}/linesurfConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/linesurfConfig.cmake ${PROJECT_BINARY_DIR}/linesurfConfigVersion.cmake
        DESTINATION ${LINESURF_CMAKE_DIR})

# Consumer test: install into a scratch prefix, configure + build tests/package against it with
# find_package(linesurf REQUIRED), run it and check its output (tests/package/run.cmake).
add_test(NAME PackageConsumer
  COMMAND ${CMAKE_COMMAND} -DBUILD_DIR=${PROJECT_BINARY_DIR} -DSOURCE_DIR=${PROJECT_SOURCE_DIR}
          -DWORK_DIR=${PROJECT_BINARY_DIR}/package_test -DGENERATOR=${CMAKE_GENERATOR}
          -DCXX=${CMAKE_CXX_COMPILER}
          -P ${PROJECT_SOURCE_DIR}/tests/package/run.cmake)
set_tests_properties(PackageConsumer PROPERTIES TIMEOUT 600 RESOURCE_LOCK package_install)
