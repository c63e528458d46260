# Install rules: libtexwarp_client as a package (headers, library, CMake config `find_package(texwarp_client)` →
# texwarp::client, pkg-config texwarp_client.pc) in component "client", and the `texwarp` CLI and texwarpd in
# component "tools" (a full configure only).
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(TEXWARP_CLIENT_CMAKE_DIR ${CMAKE_INSTALL_LIBDIR}/cmake/texwarp_client)

# Headers: the client's, and proto's type headers (those that do not include nlohmann-json: the codecs stay inside).
install(DIRECTORY ${PROJECT_SOURCE_DIR}/client/lib/include/texwarp DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}
  COMPONENT client FILES_MATCHING PATTERN "*.hpp")
file(GLOB texwarp_proto_headers ${PROJECT_SOURCE_DIR}/proto/include/texwarp/proto/*.hpp)
foreach(header IN LISTS texwarp_proto_headers)
  file(STRINGS ${header} json_lines REGEX "#include <nlohmann/")
  if(NOT json_lines)
    install(FILES ${header} DESTINATION ${CMAKE_INSTALL_INCLUDEDIR}/texwarp/proto COMPONENT client)
  endif()
endforeach()

# The library; a static one brings proto's objects as libtexwarp_proto.a (texwarp::proto, link only).
if(TEXWARP_CLIENT_SHARED)
  set(texwarp_client_install_targets texwarp_client)
  set(TEXWARP_CLIENT_PC_LIBS "-ltexwarp_client")
else()
  set(texwarp_client_install_targets texwarp_client texwarp_proto)
  set(TEXWARP_CLIENT_PC_LIBS
    "-ltexwarp_client -ltexwarp_proto -pthread -Wl,--exclude-libs,libtexwarp_client.a:libtexwarp_proto.a")
endif()
install(TARGETS ${texwarp_client_install_targets} EXPORT texwarpClientTargets
  ARCHIVE DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT client
  LIBRARY DESTINATION ${CMAKE_INSTALL_LIBDIR} COMPONENT client NAMELINK_COMPONENT client
  RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT client)
install(EXPORT texwarpClientTargets NAMESPACE texwarp:: DESTINATION ${TEXWARP_CLIENT_CMAKE_DIR} COMPONENT client)

set(TEXWARP_CLIENT_STATIC ON)
if(TEXWARP_CLIENT_SHARED)
  set(TEXWARP_CLIENT_STATIC OFF)
endif()
configure_package_config_file(${PROJECT_SOURCE_DIR}/cmake/texwarp_clientConfig.cmake.in
  ${PROJECT_BINARY_DIR}/texwarp_clientConfig.cmake INSTALL_DESTINATION ${TEXWARP_CLIENT_CMAKE_DIR})
# 0.x: a new minor version may change the API, so only the same major.minor satisfies a request.
write_basic_package_version_file(${PROJECT_BINARY_DIR}/texwarp_clientConfigVersion.cmake
  VERSION ${PROJECT_VERSION} COMPATIBILITY SameMinorVersion)
install(FILES ${PROJECT_BINARY_DIR}/texwarp_clientConfig.cmake ${PROJECT_BINARY_DIR}/texwarp_clientConfigVersion.cmake
  DESTINATION ${TEXWARP_CLIENT_CMAKE_DIR} COMPONENT client)

# The .pc file finds its prefix from where it lies (${pcfiledir}), so `cmake --install --prefix P` anywhere works.
file(RELATIVE_PATH TEXWARP_CLIENT_PC_PREFIX "/p/${CMAKE_INSTALL_LIBDIR}/pkgconfig" "/p")
configure_file(${PROJECT_SOURCE_DIR}/cmake/texwarp_client.pc.in ${PROJECT_BINARY_DIR}/texwarp_client.pc @ONLY)
install(FILES ${PROJECT_BINARY_DIR}/texwarp_client.pc DESTINATION ${CMAKE_INSTALL_LIBDIR}/pkgconfig COMPONENT client)

if(NOT TEXWARP_CLIENT_ONLY)
  install(TARGETS texwarp texwarpd RUNTIME DESTINATION ${CMAKE_INSTALL_BINDIR} COMPONENT tools)
endif()
