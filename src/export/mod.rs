//! Outputs made from a finished take's trajectories, beside its renders: what a device on a
//! wearer's head would have recorded. Today the Project Aria streams (`aria`: device
//! trajectory, calibration, IMU and eye gaze in the formats projectaria-tools reads), built on
//! the IMU measurement and error model (`imu`) and the gaze model (`gaze`). Each output is a function of the take (head poses per
//! wearer) and the rig; none reads images.

pub mod aria;
pub mod gaze;
pub mod imu;
