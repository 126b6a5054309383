"""The HTTP edge: everything between a connection and a worker's job.

In the order a request meets it: the connection guard below the application
(:mod:`.connection_guard`: header limits and deadlines), the middlewares
(:mod:`.request_context`: request id and access log; :mod:`.api_key`;
:mod:`.middleware`: the body's size and time limits, ``HEAD``, the trailing slash), the
endpoints (:mod:`.routes`) with their shared start (:mod:`.shape_request`: the query
options of :mod:`.query`, the ``Accept`` header of :mod:`.negotiation`, the bodies of
:mod:`.bodies` and :mod:`.scan`), the request and answer models (:mod:`.schemas`) and the
one request builder that turns checked options into the worker's jobs
(:mod:`.builder`).

Nothing here prunes: a job goes to :mod:`service.worker`, and what cannot become one is
refused with the problem the error table (:mod:`service.errors`) maps it to.
"""
