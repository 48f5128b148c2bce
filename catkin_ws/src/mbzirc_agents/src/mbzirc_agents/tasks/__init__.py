"""Task modules of the UAV and UGV agents (one module per group of tasks)."""
