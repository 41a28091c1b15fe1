//! Light transport on the CPU (being written).
