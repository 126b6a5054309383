"""HTTP plumbing of the endpoints: content negotiation (:mod:`.negotiation`), the query
options (:mod:`.query`) and the request bodies with their guards (:mod:`.bodies`).

Nothing here knows the worker's jobs: it turns headers and bytes into checked values or
refuses them with the problem the error table maps them to.
"""
