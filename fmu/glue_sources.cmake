# The C files of the FMU binary's own glue: the FMI 2.0 entry points and the FMU state. Included by
# fmu/, tests/ (the out-of-memory test links them in) and fuzz/ (the FMU-state target), each
# prefixing the folder it sees fmu/ at.
set(SPRINGMASS_FMU_GLUE_SOURCES fmu_cosim.c fmu_values.c fmu_derivatives.c fmu_step.c fmu_state.c)
