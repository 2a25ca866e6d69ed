//! The measured-frequency tracker (`cablevib::measured`): signals with known modes
//! (tracking), hostile input and bounded work (hostile). The allocation count of a cycle
//! with vibration input is in tests/allocations.
mod hostile;
mod tracking;
