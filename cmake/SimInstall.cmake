# Installs the library, headers, tools and a CMake package so consumers can write
#   find_package(sim REQUIRED)  target_link_libraries(app PRIVATE sim::sim)
# and a pkg-config file for everyone else.
include(CMakePackageConfigHelpers)

install(TARGETS sim_shared sim_static EXPORT simTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/sim DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        FILES_MATCHING PATTERN "*.h" PATTERN "*.hpp")
install(EXPORT simTargets NAMESPACE sim:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sim)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/simConfig.cmake.in
  ${PROJECT_BINARY_DIR}/simConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sim)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/simConfigVersion.cmake
  COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/simConfig.cmake ${PROJECT_BINARY_DIR}/simConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sim)

# The .pc file finds its prefix relative to itself, so an installed tree can be moved.
file(RELATIVE_PATH SIM_PC_TO_PREFIX "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
configure_file(${PROJECT_SOURCE_DIR}/cmake/sim.pc.in ${PROJECT_BINARY_DIR}/sim.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/sim.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig)
