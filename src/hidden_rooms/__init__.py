"""Python helpers of the hidden_rooms package (batch analysis driver and plots)."""
