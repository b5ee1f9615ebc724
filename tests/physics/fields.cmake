# Electrical and thermal fields and the interface laws they use: hand-computed law
# values and finite-difference derivatives (unit); closed forms of docs/VERIFICATION.md
# (uniform rod, two-block contact, current conservation, Joule-heated rod, adiabatic
# Joule heating, Stefan problem, backward-Euler slope, energy balance; verification).
rsw_test(test_interface_laws LABEL unit SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_interface_laws.cpp LIBS rsw_physics)
rsw_test(test_electrical LABEL verification SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_electrical.cpp LIBS rsw_physics)
rsw_test(test_thermal LABEL verification SOURCES ${CMAKE_CURRENT_LIST_DIR}/test_thermal.cpp LIBS rsw_physics)
