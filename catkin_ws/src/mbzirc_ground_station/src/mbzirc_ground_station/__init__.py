"""Web ground station of the Challenge 3 team: the whole trial on one page, live or replayed from a bag."""
