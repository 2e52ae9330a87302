# Installs the library, headers, tools, configs, a CMake package so consumers can write
#   find_package(sim REQUIRED)  target_link_libraries(app PRIVATE sim::sim)   # or sim::sim_static
# and pkg-config files (sim.pc for the shared library, sim_static.pc for the static one).
# Components, one per Debian package (cmake/SimPackaging.cmake): runtime (libsim.so.N), dev
# (headers, libsim.a, CMake and pkg-config files), tools (programs and configs), python.
include(CMakePackageConfigHelpers)

install(TARGETS sim_shared sim_static EXPORT simTargets
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT runtime NAMELINK_COMPONENT dev
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT dev
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/sim DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
        COMPONENT dev FILES_MATCHING PATTERN "*.h" PATTERN "*.hpp")
install(EXPORT simTargets NAMESPACE sim:: DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sim COMPONENT dev)

configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/simConfig.cmake.in
  ${PROJECT_BINARY_DIR}/simConfig.cmake INSTALL_DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sim)
write_basic_package_version_file(${PROJECT_BINARY_DIR}/simConfigVersion.cmake
  COMPATIBILITY SameMajorVersion)
install(FILES ${PROJECT_BINARY_DIR}/simConfig.cmake ${PROJECT_BINARY_DIR}/simConfigVersion.cmake
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/cmake/sim COMPONENT dev)

# The .pc files find their prefix relative to themselves, so an installed tree can be moved.
file(RELATIVE_PATH SIM_PC_TO_PREFIX "/prefix/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/prefix")
configure_file(${PROJECT_SOURCE_DIR}/cmake/sim.pc.in ${PROJECT_BINARY_DIR}/sim.pc @ONLY)
configure_file(${PROJECT_SOURCE_DIR}/cmake/sim_static.pc.in ${PROJECT_BINARY_DIR}/sim_static.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/sim.pc ${PROJECT_BINARY_DIR}/sim_static.pc
        DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT dev)

# The drivers' sensor configurations (the drivers' --config takes any path).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/config/ DESTINATION ${CMAKE_INSTALL_DATADIR}/sim/config
        COMPONENT tools)
