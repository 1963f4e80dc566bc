//! Sensor drivers (embedded-hal-async): the MPU9250 IMU with its AK8963 magnetometer, and the MS5611 barometer.
