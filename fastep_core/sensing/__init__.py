"""What a robot senses: the planar laser scanner (laser.py)."""
