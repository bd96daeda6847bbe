"""``carom play``: a live, interactive testbed in the browser (docs/play.md).

:mod:`carom.play.live` runs a scene in real time and takes what a page does to it;
:mod:`carom.play.wire` is what travels between them (binary frames one way, checked JSON
commands the other); :mod:`carom.play.server` serves the page and its websocket on one port
(the ``play`` extra: ``pip install 'carom[play]'``); :mod:`carom.play.replay` writes a replay
page that opens from the file system.
"""
