"""rotacal.turntable"""
