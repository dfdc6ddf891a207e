# grid: Morton keys, grading and the progress line's ETA (serial helpers of core), then the distributed grid at 1, 2 and 4 ranks:
# partition, halo exchange (forward and reverse, across ranks and levels) and interpolation.
pff_add_unit(test_morton RANKS 1)
pff_add_unit(test_progress RANKS 1)
pff_add_unit(test_grade RANKS 1)
pff_add_unit(test_partition RANKS 1 2 4)
pff_add_unit(test_halo RANKS 1 2 4)
pff_add_unit(test_interp RANKS 1 2 4)
pff_add_unit(test_adapt RANKS 1 2 4)
pff_add_unit(test_adapt RANKS 2 THREADS 2)
# core: the allocator's huge-page advice (on by default, and off)
pff_add_unit(test_memory RANKS 1)
pff_add_unit(test_memory RANKS 1 ARGS -sim_huge_pages false NAME test_memory_off)
