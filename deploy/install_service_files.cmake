# Run by `cmake --install` (deploy/install.cmake sets the ROBODIFF_* variables, and
# CMAKE_INSTALL_PREFIX is the prefix of this install, `--prefix` included): the
# configuration in <sysconfdir>/robodiff and the systemd units, rewritten so that
# ExecStart= runs the installed robodiffd and every path names the installed configuration.

# The absolute directory of an install directory, by GNUInstallDirs' rule: relative ones
# lie under the prefix, except the configuration, which is /etc under / and /usr and
# /etc/opt/<name> under /opt/<name>.
function(robodiff_absolute_dir out dir)
  if(IS_ABSOLUTE "${dir}")
    set(absolute "${dir}")
  elseif(dir STREQUAL "etc" AND CMAKE_INSTALL_PREFIX MATCHES "^/(usr/?)?$")
    set(absolute "/etc")
  elseif(dir STREQUAL "etc" AND CMAKE_INSTALL_PREFIX MATCHES "^/opt/")
    set(absolute "/etc${CMAKE_INSTALL_PREFIX}")
  else()
    set(absolute "${CMAKE_INSTALL_PREFIX}/${dir}")
  endif()
  set(${out} "${absolute}" PARENT_SCOPE)
endfunction()

# Replaces every `from` in the variable named `text_var`; stops the install when there is
# none (the shipped unit changed), so that a unit never names the wrong program or file.
function(robodiff_rewrite text_var file from to)
  string(FIND "${${text_var}}" "${from}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "deploy/systemd/${file} no longer contains '${from}': "
                        "update deploy/install_service_files.cmake")
  endif()
  string(REPLACE "${from}" "${to}" rewritten "${${text_var}}")
  set(${text_var} "${rewritten}" PARENT_SCOPE)
endfunction()

robodiff_absolute_dir(bindir "${ROBODIFF_BINDIR}")
robodiff_absolute_dir(confdir "${ROBODIFF_SYSCONFDIR}")
robodiff_absolute_dir(datadir "${ROBODIFF_DATADIR}")
robodiff_absolute_dir(unitdir "${ROBODIFF_UNIT_DIR}")
set(confdir "${confdir}/robodiff")

# The configuration: installed unless a different file of that name is already there.
foreach(shipped_and_name "robodiffd.conf;robodiffd.conf" "roudi.toml;roudi.toml"
                         "cyclonedds-loopback.xml;cyclonedds.xml")
  list(GET shipped_and_name 0 shipped)
  list(GET shipped_and_name 1 name)
  set(present "$ENV{DESTDIR}${confdir}/${name}")
  if(EXISTS "${present}")
    file(SHA256 "${present}" present_hash)
    file(SHA256 "${ROBODIFF_DEPLOY_DIR}/${shipped}" shipped_hash)
    if(NOT present_hash STREQUAL shipped_hash)
      message(STATUS "Keeping: ${present} (it differs from the shipped ${datadir}/robodiff/deploy/${shipped})")
      continue()
    endif()
  endif()
  file(INSTALL DESTINATION "${confdir}" TYPE FILE RENAME "${name}" FILES "${ROBODIFF_DEPLOY_DIR}/${shipped}")
endforeach()

# The units, as shipped but for their paths (they name /usr/local/bin and /etc/robodiff).
file(READ "${ROBODIFF_DEPLOY_DIR}/systemd/robodiffd.service" robodiffd_unit)
robodiff_rewrite(robodiffd_unit robodiffd.service "/usr/local/bin/robodiffd " "${bindir}/robodiffd ")
robodiff_rewrite(robodiffd_unit robodiffd.service "/etc/robodiff/" "${confdir}/")
file(READ "${ROBODIFF_DEPLOY_DIR}/systemd/iox-roudi.service" roudi_unit)
robodiff_rewrite(roudi_unit iox-roudi.service "/etc/robodiff/" "${confdir}/")
file(WRITE "${ROBODIFF_STAGING_DIR}/robodiffd.service" "${robodiffd_unit}")
file(WRITE "${ROBODIFF_STAGING_DIR}/iox-roudi.service" "${roudi_unit}")
file(INSTALL DESTINATION "${unitdir}" TYPE FILE
     FILES "${ROBODIFF_STAGING_DIR}/robodiffd.service" "${ROBODIFF_STAGING_DIR}/iox-roudi.service")
