# scenes: the scene geometry (liquid regions, solids, option errors) at 1, 2 and 4 ranks. The geometry
# API is private to src/scenes/, so only this test sees its header.
pff_add_unit(test_geometry RANKS 1 2 4)
target_include_directories(test_geometry PRIVATE ${PROJECT_SOURCE_DIR}/src/scenes)
