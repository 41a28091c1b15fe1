//! Readers of model files (being written).
