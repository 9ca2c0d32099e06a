#include "services/pose_cells/pose_cell_config.h"
// Header-only configuration; this unit keeps the one-file-pair convention and checks the header
// compiles on its own.
