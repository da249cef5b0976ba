//! Capture sets from real MakeHuman bodies driven by real mocap, with ground truth (being written)
