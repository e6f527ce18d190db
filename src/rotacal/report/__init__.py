"""rotacal.report"""
