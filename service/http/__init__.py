"""HTTP plumbing of the endpoints: content negotiation (:mod:`.negotiation`), the query
options (:mod:`.query`), the request bodies with their guards (:mod:`.bodies`) and the
middlewares that limit a body's size and time and answer ``HEAD`` (:mod:`.middleware`).

Nothing here makes a worker's job: it turns headers and bytes into checked values or
refuses them with the problem the error table maps them to.
"""
