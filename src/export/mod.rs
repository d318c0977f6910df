//! Outputs made from a finished take's trajectories, beside its renders: what a device on a
//! wearer's head would have recorded. Today the Project Aria streams (`aria`: device
//! trajectory, calibration and IMU in the formats projectaria-tools reads), built on the IMU
//! measurement and error model (`imu`). Each output is a function of the take (head poses per
//! wearer) and the rig; none reads images.

pub mod aria;
pub mod imu;
