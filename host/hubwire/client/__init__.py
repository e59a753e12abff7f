"""The service's client, in the user's process: ``protocol`` (the socket's JSON lines, shared with
the daemon), ``connection`` (:class:`AsyncRemoteDevice`), ``remote`` (a ``Session`` stand-in under an
ordinary ``Device``), ``streams`` and ``route`` (which boards ``connect()`` reaches through
``hubwire serve``)."""
