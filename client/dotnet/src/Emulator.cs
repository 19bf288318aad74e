// canemu's own calls, outside the vendor's namespaces (canemu_vci.h): which canemud to talk to,
// stepped time, ephemeral adapters, a controller's error state. A program that must also run on
// IXXAT's assembly keeps these behind a switch of its own.
using System;
using System.Reflection;
using System.Text;
using Ixxat.Vci3;

namespace Canemu
{
  public enum TimeMode : byte { RealTime = 0, Scaled = 1, Stepped = 2 }
  public enum ErrorState : byte { Active = 0, Warning = 1, Passive = 2, BusOff = 3 }
  public enum LineState : byte { NotInitialized = 0, Offline = 1, Online = 2 }

  public struct ControllerState
  {
    public ErrorState ErrorState;
    public ushort TransmitErrorCount, ReceiveErrorCount;
    public LineState LineState;
  }

  public static class Emulator
  {
    // Talks to the canemud listening at socket from now on (null: $CANEMU_SOCKET or the default).
    public static void Connect(string socket)
    {
      Native.Check(Native.canemuConnect(socket), "Canemu.Emulator.Connect(" + socket + ")");
    }

    // Stepped time: runs the emulation that many nanoseconds further; the time after the step.
    public static ulong StepTime(ulong nanoseconds)
    {
      ulong now;
      uint hr = Native.canemuStepTime(nanoseconds, out now);
      if (hr == Native.E_INVALID_STATE)
        throw new VciException(hr, "Canemu.Emulator.StepTime: canemud does not run in stepped time (start it with --time stepped)");
      Native.Check(hr, "Canemu.Emulator.StepTime(" + nanoseconds + ")");
      return now;
    }

    public static ulong Now
    {
      get { ulong now; byte mode; Native.Check(Native.canemuGetTime(out now, out mode), "Canemu.Emulator.Now"); return now; }
    }

    public static TimeMode TimeMode
    {
      get { ulong now; byte mode; Native.Check(Native.canemuGetTime(out now, out mode), "Canemu.Emulator.TimeMode"); return (TimeMode)mode; }
    }

    // A new adapter with one controller on bus (gone with this process or RemoveDevice); its name.
    public static string CreateDevice(string bus, string name)
    {
      long id;
      var sb = new StringBuilder(64);
      Native.Check(Native.canemuCreateDevice(bus, name, out id, sb, 64), "Canemu.Emulator.CreateDevice(" + bus + ")");
      return sb.ToString();
    }

    public static void RemoveDevice(string name)
    {
      Native.Check(Native.canemuRemoveDevice(name), "Canemu.Emulator.RemoveDevice(" + name + ")");
    }

    // The error state and counters of the controller of a control unit, channel or cyclic list.
    public static ControllerState GetControllerState(object socket)
    {
      var f = socket == null ? null : socket.GetType().GetField("handle", BindingFlags.NonPublic | BindingFlags.Instance);
      if (f == null || f.FieldType != typeof(IntPtr))
        throw new VciException(Native.E_INVALIDARG, "Canemu.Emulator.GetControllerState: pass an ICanControl, ICanChannel or ICanScheduler");
      var s = new ControllerState();
      byte e, l;
      Native.Check(Native.canemuGetControllerState((IntPtr)f.GetValue(socket), out e, out s.TransmitErrorCount,
                                                   out s.ReceiveErrorCount, out l), "Canemu.Emulator.GetControllerState");
      s.ErrorState = (ErrorState)e;
      s.LineState = (LineState)l;
      return s;
    }
  }
}
