# Writes a bundled model's reference result (tests/references/<model>.csv) as the FMU carries it:
# the CSV without its first line, the command that made it, which fmpy's read_csv would take for
# the header.
#
#   cmake -DINPUT=<tests/references/model.csv> -DOUTPUT=<reference.csv> -P reference_table.cmake
foreach(var INPUT OUTPUT)
  if(NOT ${var})
    message(FATAL_ERROR "reference_table.cmake: ${var} is not set")
  endif()
endforeach()
file(READ "${INPUT}" text)
string(REGEX REPLACE "^#[^\n]*\n" "" text "${text}")
file(WRITE "${OUTPUT}" "${text}")
