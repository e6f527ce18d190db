"""rotacal.gyro"""
