# `cmake --install` of the library: headers, the layer libraries, the GLSL
# library, the data (planet presets, spectra) and a CMake package, so that an
# engine uses it with
#   find_package(atmos CONFIG REQUIRED)
#   target_link_libraries(engine PRIVATE atmos::atmos)
include(CMakePackageConfigHelpers)

install(TARGETS atmos_data atmos_physics atmos_astronomy atmos_io atmos_tables atmos_gpu atmos_post atmos_planet atmos
        EXPORT atmosTargets
        ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR}
        LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR}
        INCLUDES DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})
install(DIRECTORY ${PROJECT_SOURCE_DIR}/include/atmos DESTINATION ${CMAKE_INSTALL_INCLUDEDIR})

# The shared GLSL (the physics, the renderer's and the post-processing's
# shaders) for engines that build their own shaders on top of it, and the data.
foreach(dir physics gpu post planet)
  install(DIRECTORY ${PROJECT_SOURCE_DIR}/src/${dir}/ DESTINATION ${CMAKE_INSTALL_DATADIR}/atmos/glsl/${dir}
          FILES_MATCHING PATTERN "*.glsl")
endforeach()
install(DIRECTORY ${PROJECT_SOURCE_DIR}/data/planets ${PROJECT_SOURCE_DIR}/data/spectra
        DESTINATION ${CMAKE_INSTALL_DATADIR}/atmos)

set(ATMOS_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/atmos)
install(EXPORT atmosTargets NAMESPACE atmos:: DESTINATION ${ATMOS_CMAKE_DIR})
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/atmosConfig.cmake.in
  ${CMAKE_CURRENT_BINARY_DIR}/atmosConfig.cmake INSTALL_DESTINATION ${ATMOS_CMAKE_DIR}
  PATH_VARS CMAKE_INSTALL_DATADIR)
write_basic_package_version_file(${CMAKE_CURRENT_BINARY_DIR}/atmosConfigVersion.cmake
  COMPATIBILITY SameMinorVersion)
install(FILES ${CMAKE_CURRENT_BINARY_DIR}/atmosConfig.cmake ${CMAKE_CURRENT_BINARY_DIR}/atmosConfigVersion.cmake
        DESTINATION ${ATMOS_CMAKE_DIR})
