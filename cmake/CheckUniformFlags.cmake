# cmake -DCOMPILE_COMMANDS=<build>/compile_commands.json -P CheckUniformFlags.cmake
#
# Fails unless every translation unit of the build is compiled for the same instruction set
# and with the same sanitizers: units that disagree on -march/-m<isa> disagree on Eigen's
# alignment and vector widths, and one binary then holds two layouts of the same type.
if(NOT EXISTS "${COMPILE_COMMANDS}")
  message(FATAL_ERROR "no compile database at '${COMPILE_COMMANDS}'")
endif()
file(READ "${COMPILE_COMMANDS}" database)
string(JSON count LENGTH "${database}")
if(count EQUAL 0)
  message(FATAL_ERROR "${COMPILE_COMMANDS}: no translation units")
endif()
math(EXPR last "${count} - 1")
set(reference "")
set(reference_file "")
foreach(i RANGE ${last})
  string(JSON command GET "${database}" ${i} command)
  string(JSON source GET "${database}" ${i} file)
  # Flags that change code generation or object layout across units.
  string(REGEX MATCHALL "(^| )(-march=[^ ]+|-mtune=[^ ]+|-m(no-)?(sse|avx|fma|f16c|bmi|popcnt|lzcnt)[^ ]*|-fsanitize=[^ ]+)"
         flags "${command}")
  list(TRANSFORM flags STRIP)
  list(SORT flags)
  string(JOIN " " signature ${flags})
  if(i EQUAL 0)
    set(reference "${signature}")
    set(reference_file "${source}")
  elseif(NOT signature STREQUAL reference)
    message(FATAL_ERROR "code-generation flags differ between translation units:\n"
            "  ${reference_file}: '${reference}'\n  ${source}: '${signature}'")
  endif()
endforeach()
message(STATUS "${count} translation units, all compiled with '${reference}'")
