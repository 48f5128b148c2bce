"""smach_viewer: a live web viewer for SMACH introspection servers."""
