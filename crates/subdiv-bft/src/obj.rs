//! Minimal OBJ reader for control meshes (to come).
