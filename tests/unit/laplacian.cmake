pff_add_unit(test_laplacian RANKS 1 2 4)
