"""``osc.nav2`` on the PyBullet navigation backend (see ``actions.py``)."""
