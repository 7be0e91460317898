"""What is designed: the study (design space, fixed geometry, loads, robot), materials, the
candidate and its CadQuery geometry, validity, STL/STEP export, and spring.json's schema and
reader. The ground of the design half: it imports nothing above it (no mesh, FEA or sweep)."""
